//! `--plan FILE`, `--only KEY` and `--collect` of `reproduce` and `ablate`: an experiment's grid
//! of runs as one shell command per line, for GNU parallel (`parallel -j 2 < FILE`) or a SLURM
//! job array (`sed -n ${SLURM_ARRAY_TASK_ID}p FILE | bash`), and the outputs collected from the
//! runs' caches once they are done.
//!
//! A line is this very invocation, by the absolute path of this binary and with `--plan FILE`
//! replaced by `--only KEY`, then a comment naming the run:
//!
//! ```text
//! /…/target/release/xtask reproduce poisson --profile smoke --only poisson/easy/amber-mean/seed0-1f2e3d  # amber-mean easy seed 0: data/runs/poisson/easy/amber-mean/seed0-1f2e3d
//! ```

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use amber_experiments::{CachePolicy, PlannedRun};
use anyhow::Context;

/// How an invocation treats the grid of runs: all here (the default), planned, one, or collected.
#[derive(clap::Args, Debug)]
pub struct GridArgs {
    /// Train nothing: write one shell command per run to FILE (each trains and evaluates its run
    /// alone, for GNU parallel or a SLURM array; see README.md), after generating the data the
    /// runs read. Then rerun with --collect instead of --plan.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["only", "collect", "force"])]
    plan: Option<PathBuf>,
    /// Train and evaluate only the run of this key (its directory under the runs root, as a
    /// plan names it); write no results.
    #[arg(long, value_name = "KEY", conflicts_with = "collect")]
    only: Option<String>,
    /// Train nothing: write the results from the cached runs, failing with the list of the runs
    /// that are not done.
    #[arg(long, conflicts_with = "force")]
    collect: bool,
    /// Retrain and re-evaluate even when cached (not in a plan: a requeued line would delete
    /// its run's progress instead of resuming it).
    #[arg(long)]
    force: bool,
    /// Root of the cached runs.
    #[arg(long, value_name = "DIR", default_value = "data/runs")]
    runs: PathBuf,
}

/// What an invocation does with the experiment.
pub enum Action<'a> {
    /// Write the plan to this file.
    Plan(&'a Path),
    /// Train and evaluate the run of this key.
    Only(&'a str),
    /// Train and evaluate what the cache policy asks, then write the results.
    All,
}

impl GridArgs {
    pub fn action(&self) -> Action<'_> {
        match (&self.plan, &self.only) {
            (Some(file), _) => Action::Plan(file),
            (None, Some(key)) => Action::Only(key),
            (None, None) => Action::All,
        }
    }

    pub fn cache_policy(&self) -> CachePolicy {
        if self.force {
            CachePolicy::Retrain
        } else if self.collect {
            CachePolicy::Require
        } else {
            CachePolicy::Reuse
        }
    }

    pub fn runs_root(&self) -> &Path {
        &self.runs
    }
}

/// Writes the plan of `runs` to `file` (atomically) and says how to run and collect it.
pub fn write(file: &Path, runs: &[PlannedRun]) -> anyhow::Result<()> {
    let args = plan_args()?;
    let lines: Vec<String> = runs.iter().map(|run| line(&args, run)).collect();
    amber_experiments::write_atomic(file, (lines.join("\n") + "\n").as_bytes())?;
    // The plan is read from wherever the scheduler starts; its lines run from any directory.
    let absolute = std::path::absolute(file).with_context(|| format!("{}: no absolute path", file.display()))?;
    let plan = quote(&absolute.to_string_lossy()).into_owned();
    println!("wrote {} runs to {plan}, one command a line; run them with", runs.len());
    println!("  parallel -j 2 < {plan}    (with RAYON_NUM_THREADS = cores / jobs)");
    println!(
        "or a SLURM array: sbatch --array=1-{} --wrap \"sed -n \\${{SLURM_ARRAY_TASK_ID}}p {plan} | bash\"",
        runs.len()
    );
    println!("then write the results with\n  {} --collect", args.join(" "));
    Ok(())
}

/// The line of `run`: the invocation `args` restricted to the run, and a comment naming it.
fn line(args: &[String], run: &PlannedRun) -> String {
    format!("{} --only {}  # {}: {}", args.join(" "), quote(&run.key), run.label, run.dir.display())
}

/// This invocation, shell-quoted: this binary by its absolute path (the runs must hash their
/// configs with this code), then the arguments without `--plan FILE`.
fn plan_args() -> anyhow::Result<Vec<String>> {
    let exe = std::env::current_exe().context("cannot find the path of this binary")?;
    let mut args = vec![quote(&exe.to_string_lossy()).into_owned()];
    args.extend(without_plan(std::env::args_os().skip(1))?.iter().map(|a| quote(a).into_owned()));
    Ok(args)
}

/// `args` without `--plan FILE` (or `--plan=FILE`).
fn without_plan(args: impl Iterator<Item = OsString>) -> anyhow::Result<Vec<String>> {
    let mut kept = Vec::new();
    let mut args = args.map(|a| a.into_string().map_err(|a| anyhow::anyhow!("{a:?}: not UTF-8, cannot go in a plan")));
    while let Some(arg) = args.next() {
        let arg = arg?;
        if arg == "--plan" {
            args.next();
        } else if !arg.starts_with("--plan=") {
            kept.push(arg);
        }
    }
    Ok(kept)
}

/// `s` as one word for POSIX shells: as is when it holds no character a shell treats specially,
/// else in single quotes.
fn quote(s: &str) -> std::borrow::Cow<'_, str> {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./=,:+@%".contains(c);
    if !s.is_empty() && s.chars().all(plain) { s.into() } else { format!("'{}'", s.replace('\'', r"'\''")).into() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_a_shell_would_split_or_expand_are_quoted() {
        assert_eq!(
            quote("data/runs/poisson/easy/amber-max/seed0-1f2e3d"),
            "data/runs/poisson/easy/amber-max/seed0-1f2e3d"
        );
        assert_eq!(quote("--methods=amber-mean,cnn-32"), "--methods=amber-mean,cnn-32");
        assert_eq!(quote("my runs"), "'my runs'");
        assert_eq!(quote("it's"), r"'it'\''s'");
        assert_eq!(quote("$HOME"), "'$HOME'");
        assert_eq!(quote(""), "''");
    }

    #[test]
    fn the_plan_option_is_dropped_in_both_spellings() {
        let args = |s: &str| s.split(' ').map(OsString::from).collect::<Vec<_>>().into_iter();
        let kept = without_plan(args("reproduce poisson --plan p.txt --profile smoke --plan=q.txt --force")).unwrap();
        assert_eq!(kept, ["reproduce", "poisson", "--profile", "smoke", "--force"]);
    }
}
