//! End to end: Adam with clipping fits random targets on two small graphs.

use amber_mpn::synthetic::random_graph;
use amber_mpn::{GraphInput, Mpn, MpnConfig, TrainConfig, Trainer, mse};
use candle_core::{DType, Device, Tensor};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

#[test]
fn training_lowers_the_loss_tenfold() {
    let dev = Device::Cpu;
    let config = MpnConfig { latent_dim: 32, steps: 3, ..MpnConfig::poisson() };
    let (model, varmap) = Mpn::init(config, 0, DType::F32, &dev).unwrap();
    let mut trainer = Trainer::new(&varmap, &TrainConfig { learning_rate: 1e-3, ..TrainConfig::default() }).unwrap();
    let mut rng = StdRng::seed_from_u64(0);
    // Targets spread well beyond their mean, so a constant prediction cannot reach 1/10 of the
    // initial loss.
    let data: Vec<(GraphInput, Tensor)> = (0..2)
        .map(|i| {
            let g = GraphInput::from_batch(&random_graph(30 + 5 * i, 45, 4, 1, i as u64), DType::F32, &dev).unwrap();
            let y: Vec<f32> = (0..g.num_nodes()).map(|_| rng.random_range(0.5..1.5)).collect();
            let n = y.len();
            (g, Tensor::from_vec(y, n, &dev).unwrap())
        })
        .collect();
    let eval = |model: &Mpn| -> f32 {
        data.iter().map(|(g, y)| mse(&model.forward(g).unwrap(), y).unwrap().to_scalar::<f32>().unwrap()).sum::<f32>()
            / 2.0
    };
    let initial = eval(&model);
    for step in 0..200 {
        let (g, y) = &data[step % 2];
        let loss = mse(&model.forward_train(g, &mut rng).unwrap(), y).unwrap();
        trainer.step(&loss).unwrap();
    }
    let last = eval(&model);
    assert!(last < initial / 10.0, "loss {initial} -> {last}");
}
