//! A PLY mesh reader (Turk 1994, "The PLY Polygon File Format"): ASCII and binary little- or
//! big-endian; vertex positions, normals (`nx ny nz`) and texture coordinates (`u v`, `s t`,
//! `texture_u texture_v`, `texture_s texture_t`); faces as `vertex_indices`/`vertex_index`
//! lists, triangulated as fans. Other elements and properties are skipped. The whole file is
//! read at once and binary data is decoded with fixed strides where possible, because the
//! meshes of real scenes are tens of megabytes.

use tempera::math::{Vec2, Vec3};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlyMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
    /// Faces with fewer than three vertices, dropped.
    pub degenerate_faces: usize,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar { name: String, ty: Scalar },
    List { name: String, count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// Reads values one at a time from the body.
struct Body<'a> {
    data: &'a [u8],
    pos: usize,
    encoding: Encoding,
}

impl Body<'_> {
    fn read(&mut self, ty: Scalar) -> Result<f64, String> {
        if self.encoding == Encoding::Ascii {
            while self.data.get(self.pos).is_some_and(u8::is_ascii_whitespace) {
                self.pos += 1;
            }
            let start = self.pos;
            while self.data.get(self.pos).is_some_and(|c| !c.is_ascii_whitespace()) {
                self.pos += 1;
            }
            let word = std::str::from_utf8(&self.data[start..self.pos]).map_err(|_| "invalid text in ASCII body")?;
            if word.is_empty() {
                return Err("unexpected end of data".into());
            }
            return word.parse::<f64>().map_err(|_| format!("expected a number, found '{word}'"));
        }
        let n = ty.size();
        let bytes = self.data.get(self.pos..self.pos + n).ok_or("unexpected end of data")?;
        self.pos += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(bytes);
        if self.encoding == Encoding::Big {
            b[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}

fn parse_header(data: &[u8]) -> Result<(Encoding, Vec<Element>, usize), String> {
    let end = data.windows(10).position(|w| w == b"end_header").ok_or("missing 'end_header'")?;
    let header = std::str::from_utf8(&data[..end]).map_err(|_| "header is not text")?;
    let mut body_start = end + 10;
    if data.get(body_start) == Some(&b'\r') {
        body_start += 1;
    }
    if data.get(body_start) == Some(&b'\n') {
        body_start += 1;
    }
    let mut lines = header.lines();
    if lines.next().map(str::trim) != Some("ply") {
        return Err("not a PLY file (missing 'ply' magic)".into());
    }
    let (mut encoding, mut elements) = (None, Vec::<Element>::new());
    for line in lines {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _] => {
                encoding = Some(match *f {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Little,
                    "binary_big_endian" => Encoding::Big,
                    other => return Err(format!("unknown PLY format '{other}'")),
                })
            }
            ["element", name, count] => {
                let count = count.parse().map_err(|_| format!("bad element count '{count}'"))?;
                elements.push(Element { name: (*name).to_owned(), count, props: Vec::new() });
            }
            ["property", "list", c, i, name] => {
                let el = elements.last_mut().ok_or("property before any element")?;
                let count = Scalar::parse(c).ok_or_else(|| format!("unknown type '{c}'"))?;
                let item = Scalar::parse(i).ok_or_else(|| format!("unknown type '{i}'"))?;
                el.props.push(Property::List { name: (*name).to_owned(), count, item });
            }
            ["property", ty, name] => {
                let el = elements.last_mut().ok_or("property before any element")?;
                let ty = Scalar::parse(ty).ok_or_else(|| format!("unknown type '{ty}'"))?;
                el.props.push(Property::Scalar { name: (*name).to_owned(), ty });
            }
            _ => return Err(format!("unrecognised header line '{line}'")),
        }
    }
    Ok((encoding.ok_or("missing 'format' line")?, elements, body_start))
}

const UV_NAMES: [(&str, &str); 4] = [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")];

fn read_vertices(body: &mut Body, el: &Element, mesh: &mut PlyMesh) -> Result<(), String> {
    let index_of = |n: &str| el.props.iter().position(|p| matches!(p, Property::Scalar { name, .. } if name == n));
    let (x, y, z) = (index_of("x"), index_of("y"), index_of("z"));
    let (Some(x), Some(y), Some(z)) = (x, y, z) else { return Err("vertex element lacks x, y or z".into()) };
    let normal = match (index_of("nx"), index_of("ny"), index_of("nz")) {
        (Some(a), Some(b), Some(c)) => Some((a, b, c)),
        _ => None,
    };
    let uv = UV_NAMES.iter().find_map(|(u, v)| Some((index_of(u)?, index_of(v)?)));
    mesh.positions.reserve(el.count);
    let mut normals = normal.map(|_| Vec::with_capacity(el.count));
    let mut uvs = uv.map(|_| Vec::with_capacity(el.count));
    let mut values = vec![0.0f64; el.props.len()];
    for _ in 0..el.count {
        for (k, p) in el.props.iter().enumerate() {
            values[k] = match p {
                Property::Scalar { ty, .. } => body.read(*ty)?,
                Property::List { count, item, .. } => {
                    let n = body.read(*count)? as usize;
                    for _ in 0..n {
                        body.read(*item)?;
                    }
                    0.0
                }
            };
        }
        let v = |i: usize| values[i] as f32;
        mesh.positions.push(Vec3::new(v(x), v(y), v(z)));
        if let (Some(ns), Some((a, b, c))) = (normals.as_mut(), normal) {
            ns.push(Vec3::new(v(a), v(b), v(c)));
        }
        if let (Some(t), Some((a, b))) = (uvs.as_mut(), uv) {
            t.push(Vec2::new(v(a), v(b)));
        }
    }
    mesh.normals = normals;
    mesh.uvs = uvs;
    Ok(())
}

fn read_faces(body: &mut Body, el: &Element, mesh: &mut PlyMesh) -> Result<(), String> {
    let list = el
        .props
        .iter()
        .position(|p| matches!(p, Property::List { name, .. } if name == "vertex_indices" || name == "vertex_index"))
        .ok_or("face element lacks a vertex_indices list")?;
    mesh.indices.reserve(el.count * 2);
    let mut face = Vec::with_capacity(8);
    for _ in 0..el.count {
        for (k, p) in el.props.iter().enumerate() {
            match p {
                Property::Scalar { ty, .. } => {
                    body.read(*ty)?;
                }
                Property::List { count, item, .. } => {
                    let n = body.read(*count)?;
                    if !(0.0..=1e6).contains(&n) {
                        return Err(format!("implausible face size {n}"));
                    }
                    face.clear();
                    for _ in 0..n as usize {
                        let i = body.read(*item)?;
                        if k == list {
                            if !(0.0..u32::MAX as f64).contains(&i) {
                                return Err(format!("invalid vertex index {i}"));
                            }
                            face.push(i as u32);
                        }
                    }
                    if k == list {
                        if face.len() < 3 {
                            mesh.degenerate_faces += 1;
                        }
                        for j in 1..face.len().saturating_sub(1) {
                            mesh.indices.push([face[0], face[j], face[j + 1]]);
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

fn skip_element(body: &mut Body, el: &Element) -> Result<(), String> {
    for _ in 0..el.count {
        for p in &el.props {
            match p {
                Property::Scalar { ty, .. } => {
                    body.read(*ty)?;
                }
                Property::List { count, item, .. } => {
                    let n = body.read(*count)? as usize;
                    for _ in 0..n {
                        body.read(*item)?;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Parses a PLY file's bytes. Errors are plain messages; the caller adds the file name.
pub fn parse(data: &[u8]) -> Result<PlyMesh, String> {
    let (encoding, elements, start) = parse_header(data)?;
    // Every record takes at least a few bytes (binary: its scalars and list counts; ASCII: one
    // digit and one separator per property), so counts that the file cannot hold are refused
    // before anything is allocated for them.
    let mut least = 0u128;
    for el in &elements {
        let record: u128 = el
            .props
            .iter()
            .map(|p| match (encoding, p) {
                (Encoding::Ascii, _) => 2,
                (_, Property::Scalar { ty, .. }) => ty.size() as u128,
                (_, Property::List { count, .. }) => count.size() as u128,
            })
            .sum();
        least += el.count as u128 * record.max(1);
        let available = data.len().saturating_sub(start) as u128;
        if least > available {
            return Err(format!(
                "element '{}' claims {} records, more than the file's {available} bytes of data can hold",
                el.name, el.count
            ));
        }
    }
    let mut body = Body { data, pos: start, encoding };
    let mut mesh = PlyMesh::default();
    for el in &elements {
        match el.name.as_str() {
            "vertex" => read_vertices(&mut body, el, &mut mesh)?,
            "face" => read_faces(&mut body, el, &mut mesh)?,
            _ => skip_element(&mut body, el)?,
        }
    }
    let n = mesh.positions.len() as u32;
    if let Some(bad) = mesh.indices.iter().flatten().find(|&&i| i >= n) {
        return Err(format!("face refers to vertex {bad}, but there are only {n} vertices"));
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\nelement face 1\n\
property list uchar int vertex_indices\nend_header\n0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n4 0 1 2 3\n";

    fn binary(big: bool) -> Vec<u8> {
        let header = format!(
            "ply\nformat {} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n\
element face 1\nproperty uchar flags\nproperty list uchar uint vertex_indices\nend_header\n",
            if big { "binary_big_endian" } else { "binary_little_endian" }
        );
        let mut out = header.into_bytes();
        let f = |v: f32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
        let u = |v: u32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
        for p in [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.5]] {
            for c in p {
                out.extend_from_slice(&f(c));
            }
            out.push(200);
        }
        out.push(7);
        out.push(3);
        for i in [0, 1, 2] {
            out.extend_from_slice(&u(i));
        }
        out
    }

    #[test]
    fn ascii_quads_become_two_triangles_with_normals_and_uvs() {
        let m = parse(ASCII.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.normals.as_ref().unwrap()[2], Vec3::Z);
        assert_eq!(m.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
    }

    #[test]
    fn binary_both_byte_orders_and_extra_properties() {
        for big in [false, true] {
            let m = parse(&binary(big)).unwrap();
            assert_eq!(m.positions[2], Vec3::new(0.0, 3.0, 0.5), "big endian: {big}");
            assert_eq!(m.indices, vec![[0, 1, 2]]);
            assert!(m.normals.is_none() && m.uvs.is_none());
        }
    }

    #[test]
    fn malformed_files_are_errors_not_panics() {
        let good = binary(false);
        for cut in [0, 10, 60, good.len() - 5, good.len() - 1] {
            assert!(parse(&good[..cut]).is_err(), "truncated at {cut}");
        }
        let bad_index = ASCII.replace("4 0 1 2 3", "3 0 1 9");
        assert!(parse(bad_index.as_bytes()).unwrap_err().contains("vertex 9"));
        assert!(parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n").is_err());
        // A count the file cannot hold is refused before anything is allocated for it.
        let huge = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\n\
property float y\nproperty float z\nend_header\n\0\0\0\0";
        let e = parse(huge).unwrap_err();
        assert!(e.contains("4000000000000") && e.contains("can hold"), "{e}");
    }
}
