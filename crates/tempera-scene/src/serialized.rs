//! Mitsuba's `.serialized` mesh format (Mitsuba 0.6 documentation, §8.1 "serialized"): a
//! sequence of meshes, each a little-endian header (`0x041C`, version 3 or 4) followed by a zlib
//! stream holding flags, (v4) a name, vertex and triangle counts, positions, optional normals,
//! texture coordinates and colours, and indices; the file ends with a table of mesh offsets and
//! the mesh count.

use std::io::Read;
use tempera::math::{Vec2, Vec3};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct SerializedMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
}

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_UVS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE: u32 = 0x2000;

struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Cursor<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let s = self.data.get(self.pos..self.pos + n).ok_or("mesh data truncated")?;
        self.pos += n;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("four bytes")))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("eight bytes")))
    }
    fn real(&mut self, double: bool) -> Result<f32, String> {
        Ok(if double {
            f64::from_le_bytes(self.take(8)?.try_into().expect("eight bytes")) as f32
        } else {
            f32::from_le_bytes(self.take(4)?.try_into().expect("four bytes"))
        })
    }
    fn vec3s(&mut self, n: usize, double: bool) -> Result<Vec<Vec3>, String> {
        (0..n).map(|_| Ok(Vec3::new(self.real(double)?, self.real(double)?, self.real(double)?))).collect()
    }
}

/// Offsets of the meshes in a file, from the table at its end.
fn mesh_offsets(data: &[u8]) -> Result<Vec<usize>, String> {
    if data.len() < 8 {
        return Err("file too short".into());
    }
    let version = u16::from_le_bytes([data[2], data[3]]);
    let count = u32::from_le_bytes(data[data.len() - 4..].try_into().expect("four bytes")) as usize;
    let width = if version >= 4 { 8 } else { 4 };
    let table = count.checked_mul(width).and_then(|t| data.len().checked_sub(4 + t)).ok_or("corrupt mesh table")?;
    (0..count)
        .map(|i| {
            let at = table + i * width;
            let off = if width == 8 {
                u64::from_le_bytes(data[at..at + 8].try_into().expect("eight bytes")) as usize
            } else {
                u32::from_le_bytes(data[at..at + 4].try_into().expect("four bytes")) as usize
            };
            if off.checked_add(4).is_none_or(|end| end > data.len()) {
                Err("mesh offset beyond the end of the file".into())
            } else {
                Ok(off)
            }
        })
        .collect()
}

/// Reads mesh `index` of a `.serialized` file's bytes.
pub fn parse(data: &[u8], index: usize) -> Result<SerializedMesh, String> {
    let offsets = mesh_offsets(data)?;
    let start = *offsets
        .get(index)
        .ok_or_else(|| format!("shapeIndex {index} out of range (the file holds {} meshes)", offsets.len()))?;
    let magic = u16::from_le_bytes([data[start], data[start + 1]]);
    let version = u16::from_le_bytes([data[start + 2], data[start + 3]]);
    if magic != MAGIC || !(3..=4).contains(&version) {
        return Err(format!("not a Mitsuba serialized mesh (header {magic:#06x}, version {version})"));
    }
    let mut raw = Vec::new();
    // Deflate expands at most 1032-fold: a longer stream is not a valid mesh, and reading it
    // whole would let a small file fill memory.
    let compressed = &data[start + 4..];
    let limit = compressed.len() as u64 * 1032 + 1024;
    flate2::read::ZlibDecoder::new(compressed)
        .take(limit)
        .read_to_end(&mut raw)
        .map_err(|e| format!("corrupt zlib stream: {e}"))?;
    let mut c = Cursor { data: &raw, pos: 0 };
    let flags = c.u32()?;
    if version >= 4 {
        let end = raw[c.pos..].iter().position(|&b| b == 0).ok_or("unterminated mesh name")?;
        c.pos += end + 1;
    }
    let (nv, nt) = (c.u64()?, c.u64()?);
    if nv > (1 << 32) || nt > (1 << 32) || nv * 12 > raw.len() as u64 {
        return Err(format!("implausible mesh size ({nv} vertices, {nt} triangles)"));
    }
    let (nv, nt) = (nv as usize, nt as usize);
    let double = flags & DOUBLE != 0;
    let positions = c.vec3s(nv, double)?;
    let normals = if flags & HAS_NORMALS != 0 { Some(c.vec3s(nv, double)?) } else { None };
    let uvs = if flags & HAS_UVS != 0 {
        Some((0..nv).map(|_| Ok(Vec2::new(c.real(double)?, c.real(double)?))).collect::<Result<Vec<_>, String>>()?)
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        c.vec3s(nv, double)?;
    }
    let wide = nv > u32::MAX as usize;
    let index_bytes = if wide { 24 } else { 12 };
    if nt.checked_mul(index_bytes).is_none_or(|b| b > raw.len() - c.pos.min(raw.len())) {
        return Err(format!("{nt} triangles do not fit in the mesh's {} bytes of data", raw.len()));
    }
    let mut indices = Vec::with_capacity(nt);
    for _ in 0..nt {
        let mut t = [0u32; 3];
        for v in &mut t {
            let i = if wide { c.u64()? } else { u64::from(c.u32()?) };
            if i >= nv as u64 {
                return Err(format!("triangle refers to vertex {i}, but there are only {nv}"));
            }
            *v = i as u32;
        }
        indices.push(t);
    }
    Ok(SerializedMesh { positions, normals, uvs, indices })
}

/// Writes meshes in the version-4 format (single precision; used by tests and tools).
pub fn write(meshes: &[SerializedMesh]) -> Vec<u8> {
    use std::io::Write;
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for m in meshes {
        offsets.push(out.len() as u64);
        out.extend_from_slice(&MAGIC.to_le_bytes());
        out.extend_from_slice(&4u16.to_le_bytes());
        let mut body = Vec::new();
        let flags =
            0x1000 | if m.normals.is_some() { HAS_NORMALS } else { 0 } | if m.uvs.is_some() { HAS_UVS } else { 0 };
        body.extend_from_slice(&flags.to_le_bytes());
        body.extend_from_slice(b"mesh\0");
        body.extend_from_slice(&(m.positions.len() as u64).to_le_bytes());
        body.extend_from_slice(&(m.indices.len() as u64).to_le_bytes());
        let f = |b: &mut Vec<u8>, v: f32| b.extend_from_slice(&v.to_le_bytes());
        for p in &m.positions {
            p.to_array().iter().for_each(|&v| f(&mut body, v));
        }
        for n in m.normals.iter().flatten() {
            n.to_array().iter().for_each(|&v| f(&mut body, v));
        }
        for uv in m.uvs.iter().flatten() {
            uv.to_array().iter().for_each(|&v| f(&mut body, v));
        }
        for t in &m.indices {
            t.iter().for_each(|i| body.extend_from_slice(&i.to_le_bytes()));
        }
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&body).expect("writing to memory");
        out.extend_from_slice(&z.finish().expect("writing to memory"));
    }
    for o in &offsets {
        out.extend_from_slice(&o.to_le_bytes());
    }
    out.extend_from_slice(&(meshes.len() as u32).to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(z: f32) -> SerializedMesh {
        SerializedMesh {
            positions: vec![Vec3::new(0.0, 0.0, z), Vec3::new(1.0, 0.0, z), Vec3::new(0.0, 1.0, z)],
            normals: Some(vec![Vec3::Z; 3]),
            uvs: Some(vec![Vec2::ZERO, Vec2::X, Vec2::Y]),
            indices: vec![[0, 1, 2]],
        }
    }

    #[test]
    fn round_trips_and_selects_by_index() {
        let bytes = write(&[tri(0.0), tri(5.0)]);
        assert_eq!(parse(&bytes, 0).unwrap(), tri(0.0));
        assert_eq!(parse(&bytes, 1).unwrap(), tri(5.0));
        assert!(parse(&bytes, 2).unwrap_err().contains("out of range"));
    }

    #[test]
    fn corrupt_files_are_errors() {
        let bytes = write(&[tri(0.0)]);
        for cut in [0, 3, 7, bytes.len() / 2, bytes.len() - 1] {
            assert!(parse(&bytes[..cut], 0).is_err(), "cut at {cut}");
        }
        let mut bad = bytes.clone();
        bad[0] = 0;
        assert!(parse(&bad, 0).is_err());
    }

    /// Inputs found by fuzzing (`fuzz/`): each is an error, not an abort.
    #[test]
    fn fuzzed_inputs_are_errors() {
        // A triangle count of 2^32 in a 100-byte file: the index buffer was allocated (48 GB)
        // before the data ran out.
        let huge_triangle_count: &[u8] = &[
            28, 4, 4, 0, 120, 156, 99, 16, 91, 96, 200, 77, 45, 206, 96, 96, 102, 128, 0, 70, 6, 108, 160, 193, 30, 23,
            31, 164, 158, 9, 136, 1, 157, 61, 3, 67, 28, 4, 4, 0, 120, 156, 99, 16, 96, 96, 200, 77, 45, 206, 96, 96,
            102, 128, 0, 70, 6, 116, 224, 224, 192, 192, 208, 96, 143, 96, 131, 0, 136, 15, 97, 131, 212, 51, 28, 1, 0,
            195, 125, 4, 195, 0, 0, 0, 0, 0, 0, 0, 0, 36, 0, 0, 0, 0, 0, 0, 0, 2, 0, 0, 0,
        ];
        // A mesh offset of 2^64 − 1: adding the header's length wrapped around.
        let wrapping_offset: &[u8] = &[
            28, 4, 4, 0, 120, 156, 156, 99, 16, 96, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255,
            255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 2, 0, 0, 0,
        ];
        assert!(parse(wrapping_offset, 0).unwrap_err().contains("offset"));
        for index in [0, 1] {
            let e = parse(huge_triangle_count, index).unwrap_err();
            assert!(e.contains("triangles") || e.contains("implausible") || e.contains("corrupt"), "{e}");
        }
    }
}
