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

/// The average follows its formula: after update t it is d_t·average + (1 − d_t)·weights, with
/// d_t = min(decay, (1 + t)/(10 + t)); it is the network `inference_network` and `save` give, and
/// a trainer resumed from its file and the trained weights continues the same average.
#[test]
fn the_weight_average_follows_the_weights_and_resumes() {
    let config = MpnConfig::small(8, 2);
    let objective = Objective::SoftplusMse;
    let decay = 0.5;
    let g = random_graph(20, 30, 4, 1, 3);
    let y = vec![1.0f32; g.num_nodes];
    let new = || MpnTrainer::new(config.clone(), objective, 0, None, Backend::Cpu).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str| dir.path().join(format!("{name}.safetensors"));
    // Every weight of a network, in name order, as `save` writes them.
    let weights = |save: &dyn Fn(&std::path::Path)| -> Vec<f32> {
        let path = file("scratch");
        save(&path);
        let mut tensors: Vec<_> =
            candle_core::safetensors::load(&path, &candle_core::Device::Cpu).unwrap().into_iter().collect();
        tensors.sort_by(|a, b| a.0.cmp(&b.0));
        tensors.into_iter().flat_map(|(_, t)| t.flatten_all().unwrap().to_vec1::<f32>().unwrap()).collect()
    };

    let mut plain = new();
    let mut averaged = new().with_weight_average(decay, None).unwrap();
    let mut expected = weights(&|p| plain.save(p).unwrap());
    assert_eq!(weights(&|p| averaged.save(p).unwrap()), expected);
    let (mut rng_plain, mut rng_averaged) = (StdRng::seed_from_u64(1), StdRng::seed_from_u64(1));
    for t in 1..=3u64 {
        plain.train_step(&g, &y, 1e-2, &mut rng_plain).unwrap();
        averaged.train_step(&g, &y, 1e-2, &mut rng_averaged).unwrap();
        let d = decay.min((1 + t) as f64 / (10 + t) as f64) as f32;
        let w = weights(&|p| plain.save(p).unwrap());
        expected = expected.iter().zip(&w).map(|(a, w)| d * a + (1.0 - d) * w).collect();
    }
    // The same trained weights; the saved network is the average, which lags behind them.
    let trained = weights(&|p| plain.save(p).unwrap());
    assert_eq!(weights(&|p| averaged.save_trained(p).unwrap()), trained);
    let average = weights(&|p| averaged.save(p).unwrap());
    assert!(average.iter().zip(&expected).all(|(a, e)| (a - e).abs() <= 1e-6 * e.abs().max(1.0)));
    assert_ne!(average, trained);
    assert_eq!(
        averaged.inference_network().predict(&g).unwrap(),
        amber_mpn::Mpn::load(&file("scratch")).unwrap().predict(&g).unwrap()
    );

    // Resumed from the trained weights, the average and the moments, one more step gives what
    // the uninterrupted trainer gives.
    averaged.save_trained(&file("trained")).unwrap();
    averaged.save(&file("average")).unwrap();
    averaged.save_optimiser(&file("moments")).unwrap();
    let mut resumed = MpnTrainer::load(&file("trained"), objective, None, Backend::Cpu)
        .unwrap()
        .with_weight_average(decay, Some(&file("average")))
        .unwrap();
    resumed.load_optimiser(&file("moments"), averaged.optimiser_steps()).unwrap();
    let mut rng_resumed = rng_averaged.clone();
    averaged.train_step(&g, &y, 1e-2, &mut rng_averaged).unwrap();
    resumed.train_step(&g, &y, 1e-2, &mut rng_resumed).unwrap();
    assert_eq!(weights(&|p| resumed.save(p).unwrap()), weights(&|p| averaged.save(p).unwrap()));
    assert!(new().with_weight_average(1.0, None).is_err());
}
