//! End to end: the training handle (Adam with clipping) fits random targets on two small graphs.

use amber_graph::GraphBatch;
use amber_mpn::synthetic::random_graph;
use amber_mpn::{MpnConfig, MpnTrainer};
use amber_nn::{Backend, Objective};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

#[test]
fn training_lowers_the_loss_tenfold() {
    let config = MpnConfig::small(32, 3);
    let objective = Objective::SoftplusMse;
    let mut trainer = MpnTrainer::new(config, objective, 0, Some(0.5), Backend::Cpu).unwrap();
    let mut rng = StdRng::seed_from_u64(0);
    // Targets spread well beyond their mean, so a constant prediction cannot reach 1/10 of the
    // initial loss.
    let data: Vec<(GraphBatch, Vec<f32>)> = (0..2)
        .map(|i| {
            let g = random_graph(30 + 5 * i, 45, 4, 1, i as u64);
            let y: Vec<f32> = (0..g.num_nodes).map(|_| rng.random_range(0.5..1.5)).collect();
            (g, y)
        })
        .collect();
    let eval = |trainer: &MpnTrainer| -> f32 {
        let mse = |(g, y): &(GraphBatch, Vec<f32>)| {
            let p = trainer.network().predict(g).unwrap();
            let size = |z: f32| objective.size(f64::from(z), None) as f32;
            p.iter().zip(y).map(|(&p, y)| (size(p) - y).powi(2)).sum::<f32>() / y.len() as f32
        };
        data.iter().map(mse).sum::<f32>() / 2.0
    };
    let initial = eval(&trainer);
    for step in 0..200 {
        let (g, y) = &data[step % 2];
        let report = trainer.train_step(g, y, 1e-3, &mut rng).unwrap();
        assert_eq!(report.squared_errors.len(), g.num_nodes);
        assert!(report.loss.is_finite() && report.grad_norm > 0.0);
    }
    assert_eq!(trainer.optimiser_steps(), 200);
    let last = eval(&trainer);
    assert!(last < initial / 10.0, "loss {initial} -> {last}");
}
