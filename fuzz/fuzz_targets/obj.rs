//! The OBJ reader on arbitrary bytes, then the triangle mesh built from what it read.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = tempera_scene::obj::parse(data) {
        let _ = tempera::geometry::TriangleMesh::new(m.positions, m.indices, m.normals, m.uvs);
    }
});
