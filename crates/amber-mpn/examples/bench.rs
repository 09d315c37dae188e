//! Runs `xtask/src/bench_mpn.rs` until `cargo xtask bench-mpn` is wired:
//! `cargo run --release -p amber-mpn --example bench -- --help`.

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[path = "../../../xtask/src/bench_mpn.rs"]
mod bench_mpn;

#[derive(clap::Parser)]
struct Cli {
    #[command(flatten)]
    args: bench_mpn::Args,
}

/// `mi_option_purge_decommits` in mimalloc's `mi_option_e` (v2 and v3).
const MI_OPTION_PURGE_DECOMMITS: libmimalloc_sys::mi_option_t = 5;

fn main() -> anyhow::Result<()> {
    // Reset freed pages (MADV_FREE) instead of decommitting them: candle allocates and frees tens
    // of MB per op, and re-faulting fresh zeroed pages nearly doubled the CPU time of a training
    // step (measured on the 50k-node graph: 5.7 → 3.2 CPU-s).
    // SAFETY: sets a process-wide allocator option; called before any other thread exists.
    unsafe { libmimalloc_sys::mi_option_set(MI_OPTION_PURGE_DECOMMITS, 0) };
    bench_mpn::run(<Cli as clap::Parser>::parse().args)
}
