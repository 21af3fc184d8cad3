//! Writing a [`Mesh`] to a file other tools read: Wavefront OBJ (text) and glTF 2.0 binary (GLB),
//! both of which [`super::load_mesh`] reads back to the same triangles.
//!
//! Owns the format choice by extension and the two encoders; the bytes reach the disk through
//! [`crate::output::atomic`], so a failed write leaves no file behind. Does not build meshes
//! (`mesh.rs`, `lathe.rs`) or read files (the rest of `mesh_io`).
//!
//! Both formats keep the mesh exactly: every f32 is written so that it parses back to the same
//! bits (OBJ: Rust's shortest round-trip decimal; GLB: the little-endian bytes), vertices keep
//! their order and sharing (a crease's duplicated ring stays two rings), and triangles keep their
//! order and counter-clockwise winding. The mesh has no texture coordinates, so none are written.

mod glb;
mod obj;

use std::path::Path;

use crate::raster::mesh::Mesh;
use crate::{Error, Result};

/// The extensions [`MeshFileFormat::from_path`] accepts.
pub const EXPORT_EXTENSIONS: &str = ".obj, .glb";

/// A mesh file shikki writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFileFormat {
    /// Wavefront OBJ: `v`, `vn` and `f v//vn` lines.
    Obj,
    /// glTF 2.0 binary: one JSON chunk and one BIN chunk.
    Glb,
}

impl MeshFileFormat {
    /// By extension, any case: `.obj` or `.glb`; anything else is an error naming those.
    pub fn from_path(path: &Path) -> Result<Self> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("obj") => Ok(MeshFileFormat::Obj),
            Some("glb") => Ok(MeshFileFormat::Glb),
            _ => Err(Error::invalid(
                "output",
                path.display(),
                format!("unknown mesh file type; valid extensions: {EXPORT_EXTENSIONS}"),
            )),
        }
    }
}

/// The file's bytes. `name` becomes the OBJ object and the glTF mesh and node name. The mesh is
/// validated first: a file that could not load back is never written.
pub fn encode_mesh(mesh: &Mesh, format: MeshFileFormat, name: &str) -> Result<Vec<u8>> {
    mesh.validate()?;
    match format {
        MeshFileFormat::Obj => Ok(obj::encode(mesh, name).into_bytes()),
        MeshFileFormat::Glb => glb::encode(mesh, name),
    }
}

/// Encodes `mesh` in the format of `path`'s extension and writes it atomically (a failed write
/// leaves no file at `path`; see [`crate::output::atomic`]).
pub fn write_mesh(path: &Path, mesh: &Mesh, name: &str) -> Result<()> {
    let format = MeshFileFormat::from_path(path)?;
    let bytes = encode_mesh(mesh, format, name)?;
    crate::output::atomic::write_atomically(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_follows_the_extension_in_any_case_and_names_the_valid_ones() {
        assert_eq!(
            MeshFileFormat::from_path(Path::new("a/bowl.OBJ")).unwrap(),
            MeshFileFormat::Obj
        );
        assert_eq!(
            MeshFileFormat::from_path(Path::new("bowl.glb")).unwrap(),
            MeshFileFormat::Glb
        );
        for bad in ["bowl.gltf", "bowl.stl", "bowl"] {
            match MeshFileFormat::from_path(Path::new(bad)) {
                Err(Error::InvalidParameter { reason, .. }) => {
                    assert!(reason.contains(".obj, .glb"), "{reason}")
                }
                other => panic!("{bad}: {other:?}"),
            }
        }
    }

    #[test]
    fn a_mesh_that_would_not_load_back_is_refused() {
        let broken = Mesh {
            positions: vec![[0.0; 3]; 3],
            normals: vec![[0.0, 1.0, 0.0]; 3],
            indices: vec![0, 1],
        };
        for format in [MeshFileFormat::Obj, MeshFileFormat::Glb] {
            assert!(encode_mesh(&broken, format, "x").is_err());
        }
    }
}
