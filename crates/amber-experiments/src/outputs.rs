//! What every experiment writes next to `results.json`: `table.md`, the normalised-DCD bars per
//! setting, the per-step curves and the mesh galleries.

use std::path::Path;

use amber_plot::{Bar, Series, Tile, bar_chart, line_chart};

use crate::method::MethodSpec;
use crate::report::{built_from_a_clean_commit, write_atomic, write_json};
use crate::results::{ExperimentResults, RunResult};
use crate::table::{self, PaperNumber, mean};

/// A column of the experiment (a Poisson difficulty, or the Console task) and its caption.
pub(crate) struct Setting {
    pub name: String,
    pub caption: String,
}

/// Writes `results.json`, `table.md`, `ndcd_bars.png` and `ndcd_per_step_<setting>.png` into
/// `out`.
pub(crate) fn write_outputs(
    out: &Path,
    results: &ExperimentResults,
    settings: &[Setting],
    methods: &[MethodSpec],
    paper: &PaperNumber,
) -> anyhow::Result<()> {
    // The committed evidence comes from committed code: the runs' as well as the collecting
    // build's (which the command checks; a dirty build's results say so in their commit).
    let dirty = results.runs_trained_by_uncommitted_code();
    if out.starts_with("results") && built_from_a_clean_commit() && !dirty.is_empty() {
        anyhow::bail!(
            "{}: runs trained by uncommitted code cannot go under results/ from a clean commit: {}; retrain them \
             (--force) or write elsewhere (--out)",
            out.display(),
            dirty.join("; ")
        );
    }
    write_json(&out.join("results.json"), results)?;
    write_atomic(&out.join("table.md"), table::markdown(results, paper).as_bytes())?;
    let runs_of = |setting: &str, spec: &MethodSpec| -> Vec<&RunResult> {
        results.runs.iter().filter(|r| r.difficulty == setting && table::row_label(r) == spec.label()).collect()
    };
    let groups: Vec<(String, Vec<Bar>)> = settings
        .iter()
        .map(|s| {
            let bars = methods
                .iter()
                .filter_map(|spec| {
                    let of = runs_of(&s.name, spec);
                    (!of.is_empty()).then(|| Bar {
                        label: spec.label(),
                        mean: mean(of.iter().map(|r| r.ndcd)),
                        quantiles: [
                            mean(of.iter().map(|r| r.ndcd_quantiles[0])),
                            mean(of.iter().map(|r| r.ndcd_quantiles[1])),
                        ],
                    })
                })
                .collect();
            (s.caption.clone(), bars)
        })
        .collect();
    bar_chart(
        &out.join("ndcd_bars.png"),
        &format!("{}: normalised DCD on {}", results.experiment, results.evaluated_on()),
        "normalised DCD",
        &groups,
    )?;
    // The per-step curves compare methods; variants would crowd them out.
    let defaults: Vec<&MethodSpec> = methods.iter().filter(|m| m.variant.name == "default").collect();
    let curves = if defaults.is_empty() { methods.iter().collect() } else { defaults };
    for s in settings {
        let series: Vec<Series> = curves
            .iter()
            .filter_map(|spec| {
                let of = runs_of(&s.name, spec);
                let steps = of.iter().map(|r| r.ndcd_per_step.len()).min()?;
                let mut points = vec![(0.0, 1.0)];
                points.extend((0..steps).map(|t| ((t + 1) as f64, mean(of.iter().map(|r| r.ndcd_per_step[t])))));
                Some(Series { label: spec.label(), points })
            })
            .collect();
        // A task with a single setting (Console) is named once.
        let title =
            if s.name == results.experiment { s.name.clone() } else { format!("{} {}", results.experiment, s.name) };
        line_chart(
            &out.join(format!("ndcd_per_step_{}.png", s.name)),
            &format!("{title}: normalised DCD per generation step (step 0 = M⁰)"),
            "generation step",
            "normalised DCD",
            &series,
        )?;
    }
    Ok(())
}

/// A gallery row per (method, problem): steps 1, 2 and the last, then the expert.
pub(crate) fn gallery_rows<'m, M>(
    rows: &'m [(String, Vec<Vec<M>>)],
    experts: &'m [&'m M],
    tile: impl Fn(String, &'m M) -> Tile<'m>,
    elements: impl Fn(&M) -> usize,
) -> Vec<Vec<Tile<'m>>> {
    let mut tiles = Vec::new();
    for (label, per_problem) in rows {
        for (k, (meshes, expert)) in per_problem.iter().zip(experts).enumerate() {
            let mut row: Vec<Tile<'m>> = gallery_steps(meshes.len())
                .into_iter()
                .map(|t| {
                    tile(format!("{label}, problem {k}, step {}: {} el.", t + 1, elements(&meshes[t])), &meshes[t])
                })
                .collect();
            row.push(tile(format!("expert, problem {k}: {} el.", elements(expert)), expert));
            tiles.push(row);
        }
    }
    tiles
}

/// Steps 1, 2 and the last (0-based indices), as the paper's figure shows them.
fn gallery_steps(steps: usize) -> Vec<usize> {
    let mut chosen: Vec<usize> = [0, 1, steps.saturating_sub(1)].into_iter().filter(|&t| t < steps).collect();
    chosen.dedup();
    chosen
}
