//! Wavefront OBJ meshes (through `tobj`): every object of the file merged into one triangle
//! list, polygons fan-triangulated, points and lines ignored; material libraries are not read.

use std::io::BufReader;
use tempera::math::{Vec2, Vec3};

/// An OBJ file's triangles. Normals and texture coordinates are kept only when every vertex
/// of every object has them; `uvs` are as the file writes them (v up).
#[derive(Debug)]
pub struct ObjMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
}

/// Parses OBJ text. Indices are not checked against the vertex count here (the mesh
/// constructor does that).
pub fn parse(data: &[u8]) -> Result<ObjMesh, String> {
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let (models, _) = tobj::load_obj_buf(&mut BufReader::new(data), &options, |_| Err(tobj::LoadError::OpenFileFailed))
        .map_err(|e| e.to_string())?;
    let (mut p, mut n, mut uv, mut idx) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let all_normals = models.iter().all(|m| m.mesh.normals.len() == m.mesh.positions.len());
    let all_uvs = models.iter().all(|m| m.mesh.texcoords.len() * 3 == m.mesh.positions.len() * 2);
    for m in &models {
        let base = u32::try_from(p.len()).map_err(|_| "more than 2^32 vertices".to_owned())?;
        let mm = &m.mesh;
        p.extend(mm.positions.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        if all_normals {
            n.extend(mm.normals.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        }
        if all_uvs {
            uv.extend(mm.texcoords.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])));
        }
        for c in mm.indices.chunks_exact(3) {
            let at = |i: u32| base.checked_add(i).ok_or_else(|| format!("vertex index {i} out of range"));
            idx.push([at(c[0])?, at(c[1])?, at(c[2])?]);
        }
    }
    if idx.is_empty() {
        return Err("no faces (is it an OBJ file?)".to_owned());
    }
    let normals = (all_normals && !n.is_empty()).then_some(n);
    let uvs = (all_uvs && !uv.is_empty()).then_some(uv);
    Ok(ObjMesh { positions: p, normals, uvs, indices: idx })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quads_are_triangulated_and_partial_attributes_dropped() {
        let text = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";
        let m = parse(text).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices.len(), 2);
        assert_eq!(m.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
        assert!(m.normals.is_none());
        assert!(!parse(b"v 0 x 0\n").unwrap_err().is_empty());
        assert!(parse(b"ply\nformat ascii 1.0\nend_header\n").unwrap_err().contains("no faces"));
    }
}
