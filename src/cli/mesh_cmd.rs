//! `shikki mesh builtin:NAME -o FILE.obj|FILE.glb [--segments N]`: argument handling only; the
//! shapes are `raster::mesh`'s and the encoders `raster::mesh_io::export`'s.

use std::path::PathBuf;

use clap::Args;

use crate::output::atomic::discard_stale_output;
use crate::raster::mesh::{BuiltinMesh, BUILTIN_SEGMENTS};
use crate::raster::mesh_io::{write_mesh, MeshFileFormat};
use crate::Result;

#[derive(Debug, Args)]
pub struct MeshArgs {
    // The help lists `BuiltinMesh::ALL`, as `render --mesh` does.
    #[arg(value_name = "BUILTIN", help = builtin_help())]
    pub builtin: String,
    /// Output file: .obj (Wavefront OBJ text) or .glb (glTF 2.0 binary); replaced atomically.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    #[arg(long, help = segments_help())]
    pub segments: Option<u32>,
}

fn builtin_help() -> String {
    format!(
        "The built-in mesh to write, one of: {}.",
        BuiltinMesh::list()
    )
}

fn segments_help() -> String {
    format!(
        "Segments around the +Y axis ({}..={}; the other direction keeps the default's \
         proportion), for the built-ins that are tessellated; default: the tessellation \
         `shikki render` draws.",
        BUILTIN_SEGMENTS.start(),
        BUILTIN_SEGMENTS.end()
    )
}

/// A failed export never leaves a file at the output path, as a failed render does not
/// (`commands::render`). A path with an extension shikki does not write is refused before
/// anything else and left alone: no earlier `shikki mesh` can have written it.
pub fn run_mesh(args: MeshArgs) -> Result<()> {
    MeshFileFormat::from_path(&args.output)?;
    export(&args).inspect_err(|_| {
        if let Ok(true) = discard_stale_output(&args.output) {
            eprintln!(
                "removed {} from an earlier run: it is not this run's output",
                args.output.display()
            );
        }
    })
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
