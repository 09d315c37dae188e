//! What the configurations of both methods share: the named profiles (`smoke`, `quick`,
//! `paper`), how many problems a run reads, and the learning-rate schedule. A run's config is
//! written beside its results so each number traces to its settings.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The paper's optimiser for both methods (spec §5, §8): Adam at this learning rate...
pub const PAPER_LEARNING_RATE: f64 = 3e-4;
/// ... with the gradients' global norm clipped to this.
pub const PAPER_MAX_GRAD_NORM: f64 = 0.5;

/// Learning-rate schedule over the whole run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum LrSchedule {
    /// The configured rate at every step (the paper).
    Constant,
    /// Linear warm-up from 0 over the first `warmup_fraction` of the steps, then linear decay
    /// to 0 at the last step (the later version, §11.5).
    WarmupLinearDecay { warmup_fraction: f64 },
}

impl LrSchedule {
    /// The rate of 0-based step `step` of `total` for peak rate `peak`.
    pub fn rate(self, peak: f64, step: u64, total: u64) -> f64 {
        match self {
            LrSchedule::Constant => peak,
            LrSchedule::WarmupLinearDecay { warmup_fraction } => {
                let warmup = ((warmup_fraction * total as f64).ceil() as u64).min(total);
                if step < warmup {
                    peak * (step + 1) as f64 / warmup as f64
                } else {
                    peak * total.saturating_sub(step) as f64 / (total - warmup).max(1) as f64
                }
            }
        }
    }
}

/// How many of a task's problems a run reads (which task and files is the caller's to say; the
/// loops themselves take problems, not paths).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DataConfig {
    /// Training problems (a prefix of the split).
    pub train_problems: usize,
    /// Validation problems used during training (a prefix of the split).
    pub val_problems: usize,
}

impl DataConfig {
    /// The most problems of a split a run reads (a bound a machine can hold, so that a typo is
    /// an error, not an abort).
    pub const MAX_PROBLEMS: usize = 100_000;
}

impl Default for DataConfig {
    fn default() -> Self {
        Self { train_problems: 20, val_problems: 20 }
    }
}

/// A named profile: the settings of `smoke` (CI), `quick` (two CPU cores) or `paper` (GPU
/// scale) of every method's config.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// CI: a couple of minutes including dataset generation.
    Smoke,
    /// The default: ≤ 30 minutes of training on two cores.
    #[default]
    Quick,
    /// The paper's numbers (GPU scale).
    Paper,
}

impl Profile {
    /// All profiles.
    pub const ALL: [Profile; 3] = [Profile::Smoke, Profile::Quick, Profile::Paper];

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Profile::Smoke => "smoke",
            Profile::Quick => "quick",
            Profile::Paper => "paper",
        }
    }
}

impl fmt::Display for Profile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Profile {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown profile `{s}` (smoke, quick, paper)"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warmup_rises_linearly_then_decays_to_zero() {
        let s = LrSchedule::WarmupLinearDecay { warmup_fraction: 0.1 };
        let rates: Vec<f64> = (0..100).map(|t| s.rate(1.0, t, 100)).collect();
        assert!((rates[0] - 0.1).abs() < 1e-12 && (rates[9] - 1.0).abs() < 1e-12);
        assert!((rates[10] - 1.0).abs() < 1e-12 && (rates[99] - 1.0 / 90.0).abs() < 1e-12);
        assert!(rates[10..].windows(2).all(|w| w[1] < w[0]));
        assert_eq!(LrSchedule::Constant.rate(3e-4, 57, 100), 3e-4);
    }
}
