//! `shikki mesh builtin:NAME -o FILE.obj|FILE.glb [--segments N]`: argument handling only (the
//! arguments are declared in `args.rs`); the shapes are `raster::mesh`'s and the encoders
//! `raster::mesh_io::export`'s.

use super::args::MeshArgs;
use crate::raster::mesh::BuiltinMesh;
use crate::raster::mesh_io::{write_mesh, MeshFileFormat};
use crate::Result;

/// A failed export never leaves a file at the output path, as a failed render does not
/// (`commands::render`). A path with an extension shikki does not write is refused before
/// anything else and left alone: no earlier `shikki mesh` can have written it.
pub fn run_mesh(args: MeshArgs) -> Result<()> {
    MeshFileFormat::from_path(&args.output)?;
    export(&args).inspect_err(|_| super::remove_earlier_output(&args.output))
}

fn export(args: &MeshArgs) -> Result<()> {
    let builtin = BuiltinMesh::parse(&args.builtin)?;
    let mesh = match args.segments {
        Some(segments) => builtin.mesh_with_segments(segments)?,
        None => builtin.mesh(),
    };
    write_mesh(&args.output, &mesh, builtin.name())?;
    eprintln!(
        "wrote {} ({}, {} vertices, {} triangles)",
        args.output.display(),
        builtin.spec(),
        mesh.positions.len(),
        mesh.triangle_count()
    );
    Ok(())
}
