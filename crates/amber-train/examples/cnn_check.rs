//! Temporary quality check of the CNN baseline (not to be committed).
use std::path::Path;
use std::time::Instant;

use amber_tasks::poisson::read_split;
use amber_train::{CnnConfig, CnnObserver, CnnStepReport, CnnTraining, EvaluationSummary, Reference, cnn_rollouts};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

struct Print;
impl CnnObserver for Print {
    fn step(&mut self, r: &CnnStepReport, total: u64) {
        if r.step % 10 == 0 || r.step == 1 {
            println!("step {}/{total} loss {:.4} grad {:.3} images {} {:.2}s", r.step, r.loss, r.grad_norm, r.images, r.seconds);
        }
    }
}

fn main() -> anyhow::Result<()> {
    unsafe { libmimalloc_sys::mi_option_set(5, 0) };
    unsafe { libmimalloc_sys::mi_option_set(15, -1) };
    let args: Vec<String> = std::env::args().collect();
    let data = Path::new(&args[1]);
    let resolution: usize = args[2].parse()?;
    let steps: u64 = args[3].parse()?;
    let images: usize = args[4].parse()?;
    let val_count: usize = args[5].parse()?;
    let lr: f64 = args.get(6).map(|s| s.parse()).transpose()?.unwrap_or(3e-4);
    let train = read_split(&data.join("train"))?;
    let val: Vec<_> = read_split(&data.join("val"))?.into_iter().take(val_count).collect();
    let normalise_labels = args.get(7).is_none_or(|s| s == "1");
    let config = CnnConfig { resolution, steps, images_per_step: Some(images), learning_rate: lr, normalise_labels, checkpoint_interval: 1000, ..CnnConfig::quick() };
    let t = Instant::now();
    let mut training = CnnTraining::new(config, train)?;
    println!("prepared in {:.1}s", t.elapsed().as_secs_f64());
    let out = std::env::temp_dir().join(format!("cnn-check-{resolution}"));
    let t = Instant::now();
    training.run(&out, &mut Print)?;
    println!("trained in {:.1}s", t.elapsed().as_secs_f64());
    let t = Instant::now();
    let references = Reference::for_problems(&val, &training.predictor().limits)?;
    let rollouts = cnn_rollouts(training.network(), training.predictor(), &val, &references)?;
    let summary = EvaluationSummary::new(&val, &rollouts);
    println!("evaluated in {:.1}s: {}", t.elapsed().as_secs_f64(), serde_json::to_string(&summary)?);
    for r in &rollouts {
        println!("  {:?} nDCD {:.3} elements {}", r.steps[0].status, r.steps[0].metrics.normalised_dcd, r.steps[0].metrics.elements);
    }
    Ok(())
}
