//! The `amber` command line.
//!
//! `amber mesh` turns a geometry and a sizing field into a mesh file or picture.

mod mesh;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "amber", version, about = "Adaptive meshing by expert reconstruction")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh a 2D domain with a sizing field; write .vtu, .msh, .json or .png.
    Mesh(mesh::MeshArgs),
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Mesh(args) => mesh::run(args),
    }
}
