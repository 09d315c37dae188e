//! The `amber` command line.
//!
//! `amber mesh` meshes a geometry with a trained model (or a given sizing field) into a mesh file
//! or picture; `amber train` trains AMBER (on generated Poisson problems or a folder of expert
//! meshes); `amber evaluate` scores a model on a folder of expert meshes; `amber calibrate` fits a
//! model's element budget to a folder of expert meshes; `amber convert` converts between mesh file
//! formats.

mod calibrate;
mod convert;
mod cross_validate;
mod evaluate;
mod mesh;
mod train;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "amber", version, about = "Adaptive meshing by expert reconstruction")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh a geometry with a trained model (or a sizing field); write .msh, .vtu, .inp, .nas, .vtk, .mesh, .json or .png.
    Mesh(mesh::MeshArgs),
    /// Train AMBER on a folder of expert meshes (--data DIR with train/ and val/) or on Poisson
    /// problems (resumes a killed run in the same --out directory).
    Train(train::TrainArgs),
    /// Convert a mesh file: .msh, .vtu, .vtk, .nas, .inp, .mesh, .json in, any of them out.
    Convert(convert::ConvertArgs),
    /// Score a model on a folder of expert meshes: evaluation.json, evaluation.md, a picture per part.
    Evaluate(evaluate::EvaluateArgs),
    /// Estimate how a model of a folder's experts meshes unseen parts: train one model per fold of
    /// the training parts, score each on the parts it held out, pool the scores.
    CrossValidate(cross_validate::CrossValidateArgs),
    /// Fit a model's element budget to a folder of expert meshes; write it as a new model directory.
    Calibrate(calibrate::CalibrateArgs),
}

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> anyhow::Result<()> {
    // Never hand freed memory back to the OS (15 = mi_option_purge_delay, -1 = never purge): the
    // networks free and reallocate tens of MB of activations every step, and re-faulting (and
    // zeroing) those pages cost a third of an MPN training step (measured with perf).
    // SAFETY: sets a process-wide allocator option before any thread starts.
    unsafe { libmimalloc_sys::mi_option_set(15, -1) };
    match Cli::parse().command {
        Command::Mesh(args) => mesh::run(args),
        Command::Train(args) => train::train(args),
        Command::Convert(args) => convert::run(args),
        Command::Evaluate(args) => evaluate::run(args),
        Command::Calibrate(args) => calibrate::run(args),
        Command::CrossValidate(args) => cross_validate::run(args),
    }
}
