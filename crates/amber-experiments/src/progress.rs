//! Progress of long work on the terminal: a bar per training run with the recent loss and
//! throughput, and a line per validation and checkpoint (kept in the scrollback, so a log of
//! the run's quality survives).

use std::path::Path;
use std::time::Instant;

use amber_train::{EvaluationSummary, StepReport, TrainingObserver};
use indicatif::{ProgressBar, ProgressStyle};

/// Steps between progress lines when no bar can be drawn.
const LOG_INTERVAL: u64 = 100;

/// Draws a training run's progress bar; `label` names the run in every line.
pub struct TrainingProgress {
    bar: ProgressBar,
    label: String,
    started: Instant,
    window: Window,
}

/// Means over the steps since the bar's message was last refreshed.
#[derive(Default)]
struct Window {
    steps: u64,
    loss: f64,
    nodes: usize,
    seconds: f64,
}

impl TrainingProgress {
    /// A bar for a run that stands at `done` of `total` steps.
    pub fn new(label: &str, done: u64, total: u64) -> Self {
        let bar = ProgressBar::new(total).with_style(
            ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta}) {msg}")
                .expect("a valid template")
                .progress_chars("=> "),
        );
        bar.set_prefix(label.to_string());
        bar.set_position(done);
        Self { bar, label: label.into(), started: Instant::now(), window: Window::default() }
    }

    /// Prints a line above the bar (to stderr when there is no terminal to draw the bar on).
    pub fn println(&self, line: &str) {
        let line = format!("{}: {line}", self.label);
        if self.bar.is_hidden() { eprintln!("{line}") } else { self.bar.println(line) }
    }

    /// Moves the bar to `done` steps (a run that resumed there).
    pub fn set_position(&self, done: u64) {
        self.bar.set_position(done);
    }

    /// Removes the bar, leaving the printed lines.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl TrainingObserver for TrainingProgress {
    fn step(&mut self, report: &StepReport, total: u64) {
        let w = &mut self.window;
        w.steps += 1;
        w.loss += report.loss();
        w.seconds += report.seconds();
        if let StepReport::Amber(r) = report {
            w.nodes += r.nodes;
        }
        let step = report.step();
        self.bar.set_position(step);
        // Without a terminal (logs, CI) the bar is hidden: print a line every few hundred steps.
        // A CNN step takes seconds, an AMBER step a fraction of one.
        let every = match (self.bar.is_hidden(), report) {
            (true, _) => LOG_INTERVAL,
            (false, StepReport::Amber(_)) => 20,
            (false, StepReport::Cnn(_)) => 5,
        };
        if w.steps < every && step < total {
            return;
        }
        let steps = w.steps as f64;
        let loss = w.loss / steps;
        let message = match report {
            StepReport::Amber(r) => format!(
                "loss {loss:.4}, {:.0} nodes/s, buffer {:?}",
                w.nodes as f64 / w.seconds.max(1e-9),
                r.buffer_depths
            ),
            StepReport::Cnn(_) => format!("loss {loss:.4}, {:.2} s/step", w.seconds / steps),
        };
        self.window = Window::default();
        if self.bar.is_hidden() {
            self.println(&format!("step {step}/{total} ({:.0} s): {message}", self.started.elapsed().as_secs_f64()));
        } else {
            self.bar.set_message(message);
        }
    }

    fn validation(&mut self, step: u64, s: &EvaluationSummary) {
        self.validation_line(&format!("validation at step {step}"), s);
    }

    fn final_validation(&mut self, step: u64, s: &EvaluationSummary) {
        self.validation_line(
            &format!("validation at step {step} with the last generation step fitted (the saved model)"),
            s,
        );
    }

    fn checkpoint(&mut self, step: u64, dir: &Path) {
        self.bar.set_message(format!("checkpoint at step {step}: {}", dir.display()));
    }
}

impl TrainingProgress {
    /// One line of a validation's scores, `what` naming the validation.
    fn validation_line(&self, what: &str, s: &EvaluationSummary) {
        let per_step: Vec<String> = s.steps.iter().map(|t| format!("{:.3}", t.normalised_dcd)).collect();
        let last = s.steps.last();
        // A failed rollout scores as the mesh it stopped at: say what the others score.
        let failed = match last {
            Some(t) if t.failed > 0 => match t.normalised_dcd_successful {
                Some(ok) => format!("{} failed, the others {ok:.3}", t.failed),
                None => format!("{} failed", t.failed),
            },
            _ => "0 failed".into(),
        };
        self.println(&format!(
            "{what} ({:.0} s): normalised DCD per generation step {} ({:.0} elements, expert {:.0}, {failed})",
            self.started.elapsed().as_secs_f64(),
            per_step.join(", "),
            last.map_or(0.0, |t| t.elements),
            s.expert_elements,
        ));
    }
}

/// A plain counting bar for work measured in items (dataset problems, rollouts).
pub fn item_bar(label: &str, total: usize) -> ProgressBar {
    let bar = ProgressBar::new(total as u64).with_style(
        ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    bar.set_prefix(label.to_string());
    bar
}
