//! `reproduce poisson --plan` then `--collect`, end to end with the xtask binary: the plan's runs
//! run concurrently under GNU parallel, and the collected results are the numbers of the plain
//! command, bit for bit (same seeds, one thread per run).

use std::path::Path;
use std::process::{Command, Output, Stdio};

/// `cargo xtask reproduce poisson` on the smoke profile, shortened (60 AMBER steps, 2 test
/// problems: the two runs are what is checked, not their quality), its runs under `runs` and
/// its results in `out`.
fn reproduce(dir: &Path, runs: &str, out: &str) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_xtask"));
    command
        .args(["reproduce", "poisson", "--profile", "smoke", "--test-problems", "2", "--config"])
        .arg(dir.join("config.json"))
        .arg("--data-root")
        .arg(dir.join("data"))
        .arg("--runs")
        .arg(dir.join(runs))
        .arg("--out")
        .arg(dir.join(out))
        // One thread per run: the same arithmetic in both ways, and no oversubscription under
        // `parallel -j 2`. Children (parallel's jobs) inherit it.
        .env("RAYON_NUM_THREADS", "1")
        .env("RUST_BACKTRACE", "0");
    command
}

fn run(command: &mut Command) -> Output {
    let output = command.output().unwrap();
    assert!(output.status.success(), "{command:?} failed:\n{}", String::from_utf8_lossy(&output.stderr));
    output
}

/// The runs of a results file without their wall times, and each run directory's name (its
/// config hash).
fn numbers(out: &Path) -> (serde_json::Value, Vec<String>) {
    let results: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("results.json")).unwrap()).unwrap();
    let mut runs = results["runs"].clone();
    for run in runs.as_array_mut().unwrap() {
        let run = run.as_object_mut().unwrap();
        run.remove("train_seconds").unwrap();
        run.remove("eval_seconds").unwrap();
    }
    let dirs = results["config"]["runs"].as_array().unwrap().iter();
    let names =
        dirs.map(|r| Path::new(r["run_dir"].as_str().unwrap()).file_name().unwrap().to_string_lossy().into()).collect();
    (runs, names)
}

/// Whether GNU parallel runs here; outside CI (`CI` unset) its absence skips the test.
fn parallel_available() -> bool {
    let found = Command::new("parallel").arg("--version").stdout(Stdio::null()).status().is_ok_and(|s| s.success());
    assert!(
        found || std::env::var_os("CI").is_none(),
        "CI is set but GNU parallel is missing (apt-get install -y parallel)"
    );
    if !found {
        println!("skipping: GNU parallel is absent (apt-get install -y parallel)");
    }
    found
}

#[test]
fn a_plan_run_by_gnu_parallel_collects_the_numbers_of_the_plain_command() {
    if !parallel_available() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    std::fs::write(dir.join("config.json"), r#"{ "steps": 60, "checkpoint_interval": 30, "validation_interval": 0 }"#)
        .unwrap();
    run(&mut reproduce(dir, "plain-runs", "plain"));

    // One line per run, naming its run directory; the data is generated once, here.
    let plan = dir.join("plan.txt");
    run(reproduce(dir, "runs", "collected").arg("--plan").arg(&plan));
    let text = std::fs::read_to_string(&plan).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "AMBER-Mean and AMBER-Max on easy, one seed:\n{text}");
    for (line, method) in lines.iter().zip(["amber-mean", "amber-max"]) {
        let key = format!("poisson/easy/{method}/seed0-");
        assert!(line.contains(&format!("--only {key}")) && line.contains(&format!("runs/{key}")), "{line}");
    }
    assert!(dir.join("data/easy/test/index.json").exists() && dir.join("data/easy/train/seed0/index.json").exists());

    // Collecting before the runs are done names every missing run and writes nothing.
    let early = reproduce(dir, "runs", "collected").arg("--collect").output().unwrap();
    let stderr = String::from_utf8_lossy(&early.stderr);
    assert!(!early.status.success() && stderr.contains("2 of the 2 runs have no cached evaluation"), "{stderr}");
    assert!(stderr.contains("amber-mean easy seed 0") && stderr.contains("amber-max easy seed 0"), "{stderr}");
    assert!(!dir.join("collected").exists());

    let mut jobs = Command::new("parallel");
    jobs.args(["--will-cite", "-j", "2"]).stdin(std::fs::File::open(&plan).unwrap());
    run(jobs.env("RAYON_NUM_THREADS", "1").env("RUST_BACKTRACE", "0"));
    // A SLURM array task runs its line through bash; a done run is reused at once.
    let line = Command::new("bash").arg("-c").arg(format!("sed -n 2p {} | bash", plan.display())).output().unwrap();
    assert!(line.status.success() && String::from_utf8_lossy(&line.stdout).contains("reusing the evaluation"));

    run(reproduce(dir, "runs", "collected").arg("--collect"));
    assert_eq!(numbers(&dir.join("collected")), numbers(&dir.join("plain")));
}
