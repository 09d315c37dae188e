//! `table.md`: the paper's layout (normalised DCD, mean and 25–75 % quantiles per method and
//! difficulty) with the paper's number beside ours, and a second table of the raw numbers.

use std::collections::BTreeMap;
use std::fmt::Write;

use amber_stdx::median;

use crate::results::{ExperimentResults, RunResult};

/// The paper's normalised DCD of a row (method label) and column (difficulty or setting), where
/// the paper gives one.
pub type PaperNumber = dyn Fn(&str, &str) -> Option<f64>;

/// The runs of each (row, column) cell: all seeds.
type Cells<'r> = BTreeMap<(String, String), Vec<&'r RunResult>>;

/// The row labels, the column names and the cells of `results`, in the order of first appearance.
fn cells(results: &ExperimentResults) -> (Vec<String>, Vec<String>, Cells<'_>) {
    let mut rows: Vec<String> = Vec::new();
    let mut columns: Vec<String> = Vec::new();
    let mut cells = Cells::new();
    for run in &results.runs {
        let row = row_label(run);
        if !rows.contains(&row) {
            rows.push(row.clone());
        }
        if !columns.contains(&run.difficulty) {
            columns.push(run.difficulty.clone());
        }
        cells.entry((row, run.difficulty.clone())).or_default().push(run);
    }
    (rows, columns, cells)
}

/// The row label of a run: its method, plus its variant unless it is the default.
pub fn row_label(run: &RunResult) -> String {
    match run.variant.as_str() {
        "default" => run.method.clone(),
        variant => format!("{} ({variant})", run.method),
    }
}

/// The mean of `values` over seeds or problems (0 for none).
pub(crate) fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    sum / n.max(1) as f64
}

/// Each problem's final element count over its expert's, over every problem of `runs`: the median
/// [smallest, largest], or a dash without problems.
fn element_ratios(runs: &[&RunResult]) -> String {
    let ratios: Vec<f64> =
        runs.iter().flat_map(|r| &r.problems).map(|p| p.last().elements as f64 / p.expert_elements as f64).collect();
    let (low, high) = ratios.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &r| (l.min(r), h.max(r)));
    if ratios.is_empty() { "–".into() } else { format!("{:.2} [{low:.2}, {high:.2}]", median(&ratios)) }
}

/// The Markdown of both tables.
pub fn markdown(results: &ExperimentResults, paper: &PaperNumber) -> String {
    let (rows, columns, cells) = cells(results);
    let mut md = String::new();
    let seeds = results.runs.iter().map(|r| r.seed).max().map_or(0, |s| s + 1);
    let _ = writeln!(
        md,
        "# {} — profile `{}`\n\nNormalised DCD after the last generation step on {} (lower is better; \
         0 = as good as re-meshing with the expert's own sizing field, 1 = no better than M⁰): mean over problems \
         [25 %, 75 % quantiles], averaged over {seeds} seed(s){}. *Paper* is the paper's number (mean of 4 seeds) \
         where it gives one.\n",
        results.experiment,
        results.profile,
        results.evaluated_on(),
        if seeds > 1 { ", each seed's own mean after it" } else { "" }
    );
    if results.config["experiment"]["scale_to_budget"] == true {
        md.push_str(
            "Predicted fields whose estimated element count exceeds the budget (1.2 × the largest training expert) \
             are scaled up to it at evaluation (the later version's remedy, spec §11) rather than skipped as in the \
             paper; training is unchanged.\n\n",
        );
    }
    let _ = write!(md, "| method |");
    for c in &columns {
        let _ = write!(md, " {c} | paper |");
    }
    let _ = write!(md, "\n|---|");
    for _ in &columns {
        let _ = write!(md, "---|---|");
    }
    md.push('\n');
    for row in &rows {
        let _ = write!(md, "| {row} |");
        for c in &columns {
            match cells.get(&(row.clone(), c.clone())) {
                Some(runs) => {
                    let _ = write!(
                        md,
                        " {:.3} [{:.3}, {:.3}]",
                        mean(runs.iter().map(|r| r.ndcd)),
                        mean(runs.iter().map(|r| r.ndcd_quantiles[0])),
                        mean(runs.iter().map(|r| r.ndcd_quantiles[1]))
                    );
                    if runs.len() > 1 {
                        let by_seed: Vec<String> = runs.iter().map(|r| format!("{:.3}", r.ndcd)).collect();
                        let _ = write!(md, " (seeds {})", by_seed.join(", "));
                    }
                    md.push_str(" |");
                }
                None => md.push_str(" – |"),
            }
            match paper(row, c) {
                Some(p) => {
                    let _ = write!(md, " {p:.3} |");
                }
                None => md.push_str(" – |"),
            }
        }
        md.push('\n');
    }
    let _ = writeln!(
        md,
        "\n## Raw numbers\n\nMeans over the evaluated problems and seeds: raw DCD of the final mesh d(Mᵀ), of M⁰ and of the \
         reconstruction M̂ to the expert; normalised DCD per generation step; elements (expert); each \
         problem's final elements over its expert's, median [smallest, largest]; failed or over-budget \
         generation steps (summed); training and evaluation wall time.\n"
    );
    let _ = writeln!(
        md,
        "| method | setting | d(Mᵀ) | d(M⁰) | d(M̂) | nDCD per step | elements (expert) | elements / expert's | \
         volume diff. | failed steps | train s | eval s |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for row in &rows {
        for c in &columns {
            let Some(runs) = cells.get(&(row.clone(), c.clone())) else { continue };
            let steps = runs.iter().map(|r| r.ndcd_per_step.len()).min().unwrap_or(0);
            let per_step: Vec<String> =
                (0..steps).map(|t| format!("{:.3}", mean(runs.iter().map(|r| r.ndcd_per_step[t])))).collect();
            let ratios = element_ratios(runs);
            let _ = writeln!(
                md,
                "| {row} | {c} | {:.4} | {:.4} | {:.4} | {} | {:.0} ({:.0}) | {ratios} | {:.3e} | {} | {:.0} | {:.0} |",
                mean(runs.iter().map(|r| r.dcd)),
                mean(runs.iter().map(|r| r.dcd_initial)),
                mean(runs.iter().map(|r| r.dcd_reconstruction)),
                per_step.join(", "),
                mean(runs.iter().map(|r| r.elements)),
                mean(runs.iter().map(|r| r.expert_elements)),
                mean(runs.iter().map(|r| r.volume_difference)),
                runs.iter().map(|r| r.failed_steps).sum::<usize>(),
                mean(runs.iter().map(|r| r.train_seconds)),
                mean(runs.iter().map(|r| r.eval_seconds)),
            );
        }
    }
    let _ = writeln!(md, "\nCommit `{}`; machine: {}.", results.commit, results.machine);
    // A run trained by other code than the one collecting it is named, so that the table never
    // claims one commit made numbers that another did.
    for r in results.runs.iter().filter(|r| r.trained_by.as_deref().is_some_and(|c| c != results.commit)) {
        let trained_by = r.trained_by.as_deref().unwrap_or_default();
        let _ = writeln!(md, "\n{} {} seed {} was trained by `{trained_by}`.", row_label(r), r.difficulty, r.seed);
    }
    md
}

#[cfg(test)]
mod tests {
    use amber_train::{MeshMetrics, StepStatus};

    use super::*;
    use crate::results::{ProblemEvaluation, RunKey, StepEvaluation};

    fn problem(elements: usize, expert_elements: usize) -> ProblemEvaluation {
        scored(elements, expert_elements, 0.1)
    }

    fn scored(elements: usize, expert_elements: usize, normalised_dcd: f64) -> ProblemEvaluation {
        let metrics = MeshMetrics { dcd: 0.1, normalised_dcd, chamfer: 0.0, volume_difference: 0.0, elements };
        ProblemEvaluation {
            name: None,
            expert_sha256: None,
            initial: metrics,
            steps: vec![StepEvaluation { status: StepStatus::Meshed, metrics }],
            initial_dcd: 0.5,
            reconstruction_dcd: 0.0,
            expert_elements,
        }
    }

    fn key(seed: usize) -> RunKey<'static> {
        RunKey {
            method: "amber",
            variant: "default",
            difficulty: "console",
            seed,
            train_seconds: 0.0,
            eval_seconds: 0.0,
            threads: Default::default(),
        }
    }

    #[test]
    fn a_cell_of_several_seeds_shows_each_seeds_mean() {
        let runs = vec![
            RunResult::new(key(0), &[scored(10, 10, 0.1), scored(10, 10, 0.2)]),
            RunResult::new(key(1), &[scored(10, 10, 0.3), scored(10, 10, 0.4)]),
        ];
        let results = ExperimentResults::new("console", "quick", serde_json::json!({}), runs);
        let md = markdown(&results, &|_, _| Some(0.196));
        assert!(md.contains("| amber | 0.250 [0.225, 0.275] (seeds 0.150, 0.350) | 0.196 |"), "{md}");
        assert!(md.contains("averaged over 2 seed(s), each seed's own mean after it."), "{md}");
        let one = ExperimentResults::new("console", "quick", serde_json::json!({}), results.runs[..1].to_vec());
        assert!(markdown(&one, &|_, _| None).contains("| amber | 0.150 [0.125, 0.175] | – |"));
    }

    #[test]
    fn the_element_ratio_column_spans_every_problem_of_every_seed() {
        let first = RunResult::new(key(0), &[problem(90, 100), problem(300, 200)]);
        let second = RunResult::new(key(1), &[problem(50, 100)]);
        assert_eq!(element_ratios(&[&first, &second]), "0.90 [0.50, 1.50]");
        assert_eq!(element_ratios(&[]), "–");
    }
}
