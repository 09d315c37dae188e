//! `cargo xtask`: benchmarks, datasets and reproductions of the paper's experiments.

fn main() -> anyhow::Result<()> {
    Ok(())
}
