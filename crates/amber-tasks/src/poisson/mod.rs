//! The Poisson task (spec §1): −Δu = f on a random L-shape with a random Gaussian-mixture load.

mod dataset;
mod file;
mod problem;

pub use dataset::{
    DatasetManifest, Split, SplitReport, SplitRequest, load_split, problem_seeds, split_dir, write_split,
};
pub use file::{read_part, read_problem, read_split};
pub use problem::{LOG_ERROR_INDICATOR_COLUMN, LOG_LOAD_COLUMN, PoissonPart};

use std::fmt;
use std::str::FromStr;

use amber_fem::{ExpertHeuristic, GaussianMixture, GaussianMixtureParams};
use amber_mesh::Mesh2;
use amber_meshgen::{Mesh2dParams, PolygonDomain, uniform_mesh_2d};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::TaskError;

/// Target size h₀ of the initial mesh M⁰: the reference converts its maximum element volume 0.1
/// with the 3D formula, (6√2·0.1)^(1/3), which gives meshes of 6–12 triangles.
pub const INITIAL_SIZE: f64 = 0.946_67;

/// Number of Gaussian components of the load.
pub const LOAD_COMPONENTS: usize = 3;

/// How many expert refinement steps a problem gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Difficulty {
    /// 25 steps (≈1,100 expert triangles).
    Easy,
    /// 50 steps (≈7,000).
    Medium,
    /// 75 steps (≈23,500).
    Hard,
}

impl Difficulty {
    /// All difficulties, easiest first.
    pub const ALL: [Difficulty; 3] = [Difficulty::Easy, Difficulty::Medium, Difficulty::Hard];

    /// Expert refinement steps S.
    pub fn steps(self) -> usize {
        match self {
            Difficulty::Easy => 25,
            Difficulty::Medium => 50,
            Difficulty::Hard => 75,
        }
    }

    /// Lower-case name, as in paths and files.
    pub fn name(self) -> &'static str {
        match self {
            Difficulty::Easy => "easy",
            Difficulty::Medium => "medium",
            Difficulty::Hard => "hard",
        }
    }
}

impl fmt::Display for Difficulty {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Difficulty {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|d| d.name() == s)
            .ok_or_else(|| format!("unknown difficulty `{s}` (easy, medium, hard)"))
    }
}

/// Where a problem came from and how its expert mesh was made (absent fields: unknown, e.g. in
/// files of the reference implementation).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ProblemMetadata {
    /// Seed the corner and load were drawn from.
    pub seed: Option<u64>,
    /// Expert refinement steps.
    pub steps: Option<usize>,
    /// Target size of the initial mesh.
    pub initial_size: Option<f64>,
    /// Settings of the expert heuristic.
    pub heuristic: Option<ExpertHeuristic>,
}

/// One Poisson problem: domain, load, initial mesh M⁰ and expert mesh M*.
#[derive(Clone, Debug, PartialEq)]
pub struct PoissonProblem {
    /// Re-entrant corner p of the L-shape.
    pub corner: [f64; 2],
    /// The load f.
    pub load: GaussianMixture,
    /// M⁰: uniform mesh of the domain with size h₀.
    pub initial_mesh: Mesh2,
    /// M*: the expert heuristic's mesh.
    pub expert_mesh: Mesh2,
    /// Provenance.
    pub metadata: ProblemMetadata,
}

/// The random part of a problem: corner and load.
#[derive(Clone, Debug, PartialEq)]
pub struct ProblemSample {
    /// Re-entrant corner p ~ U(0.2, 0.8)².
    pub corner: [f64; 2],
    /// Load f.
    pub load: GaussianMixture,
}

impl ProblemSample {
    /// Draws corner and load from `seed` (spec §1, as the reference code does it):
    /// p ~ U(0.2, 0.8)²; means ~ U(0.1, 0.9)²; weights 1 + exp(z), z ~ N(0, 1), normalised;
    /// per-axis variances exp(U(ln 1e-4, ln 1e-3)) rotated by θ ~ U(0, 2π).
    ///
    /// The reference seeds its geometry and its load generator with the same integer, so the
    /// uniforms behind p also produce the first mean: μ₁ = 0.1 + 0.8·u = (4/3)p − 1/6, always
    /// within 0.1 of the re-entrant corner. That correlation shapes the expert meshes (a peak at
    /// the singularity), so it is reproduced here.
    pub fn draw(seed: u64) -> Result<Self, TaskError> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let u: [f64; 2] = [rng.random(), rng.random()];
        let corner = u.map(|u| 0.2 + 0.6 * u);
        let mut means = vec![u.map(|u| 0.1 + 0.8 * u)];
        while means.len() < LOAD_COMPONENTS {
            means.push([0.1 + 0.8 * rng.random::<f64>(), 0.1 + 0.8 * rng.random::<f64>()]);
        }
        let raw: Vec<f64> = (0..LOAD_COMPONENTS).map(|_| 1.0 + rng.sample::<f64, _>(StandardNormal).exp()).collect();
        let total: f64 = raw.iter().sum();
        let weights = raw.iter().map(|w| w / total).collect();
        let (lo, hi) = (1e-4f64.ln(), 1e-3f64.ln());
        let diagonals: Vec<[f64; 2]> =
            (0..LOAD_COMPONENTS).map(|_| [(), ()].map(|_| (lo + (hi - lo) * rng.random::<f64>()).exp())).collect();
        let covariances = diagonals
            .iter()
            .map(|&[d0, d1]| {
                let theta = std::f64::consts::TAU * rng.random::<f64>();
                let (s, c) = theta.sin_cos();
                let off = c * s * (d0 - d1);
                [[c * c * d0 + s * s * d1, off], [off, s * s * d0 + c * c * d1]]
            })
            .collect();
        let load = GaussianMixture::new(GaussianMixtureParams { means, covariances, weights })
            .map_err(|source| TaskError::Fem { seed, source })?;
        Ok(Self { corner, load })
    }
}

impl PoissonProblem {
    /// Generates the problem of `seed`: draws corner and load, meshes M⁰ with size
    /// `initial_size`, and runs `heuristic` for `steps` steps.
    pub fn generate(
        seed: u64,
        steps: usize,
        initial_size: f64,
        heuristic: &ExpertHeuristic,
    ) -> Result<Self, TaskError> {
        let ProblemSample { corner, load } = ProblemSample::draw(seed)?;
        let initial_mesh =
            initial_mesh(corner, initial_size).map_err(|source| TaskError::InitialMesh { seed, source })?;
        let expert_mesh =
            heuristic.run(&initial_mesh, &load, steps).map_err(|source| TaskError::Fem { seed, source })?;
        let metadata = ProblemMetadata {
            seed: Some(seed),
            steps: Some(steps),
            initial_size: Some(initial_size),
            heuristic: Some(heuristic.clone()),
        };
        Ok(Self { corner, load, initial_mesh, expert_mesh, metadata })
    }

    /// The L-shape polygon (0,0), (1,0), (1,py), (px,py), (px,1), (0,1).
    pub fn polygon(&self) -> [[f64; 2]; 6] {
        lshape_polygon(self.corner)
    }
}

/// The L-shape polygon with re-entrant corner `corner`, counter-clockwise.
pub fn lshape_polygon([px, py]: [f64; 2]) -> [[f64; 2]; 6] {
    [[0.0, 0.0], [1.0, 0.0], [1.0, py], [px, py], [px, 1.0], [0.0, 1.0]]
}

/// M⁰: a uniform mesh of the L-shape with re-entrant corner `corner` and target size `size`.
pub fn initial_mesh(corner: [f64; 2], size: f64) -> Result<Mesh2, amber_meshgen::MeshgenError> {
    uniform_mesh_2d(&PolygonDomain::lshape(corner)?, size, &Mesh2dParams::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_follow_the_reference_distribution() {
        for seed in 0..200 {
            let s = ProblemSample::draw(seed).unwrap();
            assert!(s.corner.iter().all(|&p| (0.2..0.8).contains(&p)));
            let params = s.load.params();
            assert_eq!(params.means.len(), LOAD_COMPONENTS);
            assert!(params.means.iter().flatten().all(|&m| (0.1..0.9).contains(&m)));
            // The first mean sits within 0.1 of the re-entrant corner.
            assert!((0..2).all(|k| (params.means[0][k] - s.corner[k]).abs() <= 0.1 + 1e-12));
            assert!((params.weights.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            for c in &params.covariances {
                let (trace, det) = (c[0][0] + c[1][1], c[0][0] * c[1][1] - c[0][1] * c[1][0]);
                assert!(trace > 2e-4 - 1e-12 && trace < 2e-3 + 1e-12 && det > 1e-8 - 1e-15);
            }
        }
        assert_eq!(ProblemSample::draw(7).unwrap(), ProblemSample::draw(7).unwrap());
        assert_ne!(ProblemSample::draw(7).unwrap(), ProblemSample::draw(8).unwrap());
    }

    #[test]
    fn difficulties_parse_and_count_steps() {
        assert_eq!("hard".parse::<Difficulty>().unwrap().steps(), 75);
        assert!("extreme".parse::<Difficulty>().is_err());
    }
}
