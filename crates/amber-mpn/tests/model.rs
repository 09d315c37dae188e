//! The network as a whole: parameter count, fused vs stock-candle forward and gradients,
//! gradient coverage, input validation, checkpoints.

use amber_mpn::synthetic::random_graph;
use amber_mpn::{GraphInput, Mpn, MpnConfig, MpnError, OutputTransform};
use candle_core::{DType, Device, Tensor};
use rand::SeedableRng;
use rand::rngs::StdRng;

fn small_config() -> MpnConfig {
    MpnConfig {
        latent_dim: 8,
        steps: 3,
        ..MpnConfig::poisson()
    }
}

fn graph(dtype: DType, seed: u64) -> GraphInput {
    GraphInput::from_batch(&random_graph(40, 50, 4, 1, seed), dtype, &Device::Cpu).unwrap()
}

fn values(t: &Tensor) -> Vec<f64> {
    t.to_dtype(DType::F64)
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1()
        .unwrap()
}

#[test]
fn poisson_network_has_the_papers_parameter_count() {
    let (model, varmap) = Mpn::init(MpnConfig::poisson(), 0, DType::F32, &Device::Cpu).unwrap();
    let counted: usize = model.parameters().iter().map(|p| p.elem_count()).sum();
    let stored: usize = varmap.all_vars().iter().map(|v| v.elem_count()).sum();
    assert_eq!(counted, 300_673);
    assert_eq!(stored, 300_673);
    assert_eq!(MpnConfig::poisson().num_parameters(), 300_673);
}

#[test]
fn initialisation_is_seeded() {
    let params = |seed| {
        let (m, _) = Mpn::init(small_config(), seed, DType::F32, &Device::Cpu).unwrap();
        m.parameters()
            .iter()
            .flat_map(|p| values(p))
            .collect::<Vec<_>>()
    };
    assert_eq!(params(1), params(1));
    assert_ne!(params(1), params(2));
}

#[test]
fn fused_forward_and_gradients_match_stock_candle() {
    let (model, varmap) = Mpn::init(small_config(), 3, DType::F64, &Device::Cpu).unwrap();
    let mut rng = StdRng::seed_from_u64(0);
    // A dropped graph has nodes without incoming edges, the corner case of the aggregation.
    let g = graph(DType::F64, 1).drop_edges(0.5, &mut rng).unwrap();
    let target = Tensor::rand(0.0f64, 1.0, g.num_nodes(), &Device::Cpu).unwrap();
    let fast = model.forward(&g).unwrap();
    let naive = model.forward_naive(&g).unwrap();
    for (a, b) in values(&fast).iter().zip(values(&naive)) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
    let grads = |out: &Tensor| amber_mpn::mse(out, &target).unwrap().backward().unwrap();
    let (gf, gn) = (grads(&fast), grads(&naive));
    for var in varmap.all_vars() {
        let (a, b) = (values(gf.get(&var).unwrap()), values(gn.get(&var).unwrap()));
        let scale = b.iter().fold(1e-3f64, |m, v| m.max(v.abs()));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-9 * scale, "{x} vs {y}");
        }
    }
}

#[test]
fn every_parameter_gets_a_gradient() {
    let (model, varmap) = Mpn::init(small_config(), 0, DType::F32, &Device::Cpu).unwrap();
    let mut rng = StdRng::seed_from_u64(0);
    let loss = model
        .forward_train(&graph(DType::F32, 2), &mut rng)
        .unwrap()
        .sum_all()
        .unwrap();
    let grads = loss.backward().unwrap();
    let vars = varmap.data().lock().unwrap();
    assert_eq!(vars.len(), model.parameters().len());
    for (name, var) in vars.iter() {
        let g = grads
            .get(var)
            .unwrap_or_else(|| panic!("{name} got no gradient"));
        assert!(
            values(g).iter().any(|&v| v != 0.0),
            "{name} has an all-zero gradient"
        );
    }
}

#[test]
fn f32_matches_f64() {
    let (m64, vars) = Mpn::init(small_config(), 4, DType::F64, &Device::Cpu).unwrap();
    let dir = std::env::temp_dir().join(format!("amber-mpn-f32-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("model.safetensors");
    m64.save(&vars, &path).unwrap();
    let m32 = Mpn::load(&path, DType::F32, &Device::Cpu).unwrap();
    let (a, b) = (
        values(&m64.forward(&graph(DType::F64, 3)).unwrap()),
        values(&m32.forward(&graph(DType::F32, 3)).unwrap()),
    );
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-4, "{x} vs {y}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn dropout_is_reproducible_and_only_in_training() {
    let (model, _) = Mpn::init(
        MpnConfig {
            edge_dropout: 0.3,
            ..small_config()
        },
        0,
        DType::F32,
        &Device::Cpu,
    )
    .unwrap();
    let g = graph(DType::F32, 4);
    let train = |seed| {
        values(
            &model
                .forward_train(&g, &mut StdRng::seed_from_u64(seed))
                .unwrap(),
        )
    };
    assert_eq!(train(7), train(7));
    assert_ne!(train(7), train(8));
    assert_eq!(
        values(&model.forward(&g).unwrap()),
        values(&model.forward(&g).unwrap())
    );
}

#[test]
fn output_transforms() {
    let g = graph(DType::F64, 5);
    let out = |output| {
        let (m, _) = Mpn::init(
            MpnConfig {
                output,
                ..small_config()
            },
            9,
            DType::F64,
            &Device::Cpu,
        )
        .unwrap();
        values(&m.forward(&g).unwrap())
    };
    let (raw, soft, exp) = (
        out(OutputTransform::None),
        out(OutputTransform::Softplus),
        out(OutputTransform::Exp),
    );
    for i in 0..raw.len() {
        assert!((soft[i] - raw[i].exp().ln_1p()).abs() < 1e-12);
        assert!((exp[i] - raw[i].exp()).abs() < 1e-12);
    }
}

#[test]
fn wrong_feature_dimensions_are_errors() {
    let (model, _) = Mpn::init(small_config(), 0, DType::F32, &Device::Cpu).unwrap();
    let bad_nodes =
        GraphInput::from_batch(&random_graph(10, 10, 3, 1, 0), DType::F32, &Device::Cpu).unwrap();
    assert!(matches!(
        model.forward(&bad_nodes),
        Err(MpnError::FeatureDim {
            expected: 4,
            got: 3,
            ..
        })
    ));
    let bad_edges =
        GraphInput::from_batch(&random_graph(10, 10, 4, 2, 0), DType::F32, &Device::Cpu).unwrap();
    assert!(matches!(
        model.forward(&bad_edges),
        Err(MpnError::FeatureDim {
            expected: 1,
            got: 2,
            ..
        })
    ));
    assert!(matches!(
        model.forward(&graph(DType::F64, 0)),
        Err(MpnError::InvalidGraph(_))
    ));
    let mut broken = random_graph(10, 10, 4, 1, 0);
    broken.edge_dst.reverse();
    assert!(matches!(
        model.predict(&broken),
        Err(MpnError::InvalidGraph(_))
    ));
}

#[test]
fn checkpoints_round_trip_and_reject_wrong_shapes() {
    let dir = std::env::temp_dir().join(format!("amber-mpn-ckpt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("model.safetensors");
    let (model, varmap) = Mpn::init(small_config(), 5, DType::F32, &Device::Cpu).unwrap();
    model.save(&varmap, &path).unwrap();
    let g = graph(DType::F32, 6);
    let expected = values(&model.forward(&g).unwrap());

    let plain = Mpn::load(&path, DType::F32, &Device::Cpu).unwrap();
    assert!(plain.parameters().iter().all(|p| !p.is_variable()));
    let out = plain.forward(&g).unwrap();
    assert!(
        !out.track_op(),
        "inference from plain tensors must record no graph"
    );
    assert_eq!(values(&out), expected);
    assert!(!model.for_inference().forward(&g).unwrap().track_op());
    let (trainable, vars) = Mpn::load_trainable(&path, DType::F32, &Device::Cpu).unwrap();
    assert_eq!(values(&trainable.forward(&g).unwrap()), expected);
    assert_eq!(vars.all_vars().len(), model.parameters().len());

    // The same weights under a configuration with another width or depth.
    for config in [
        MpnConfig {
            latent_dim: 16,
            ..small_config()
        },
        MpnConfig {
            steps: 2,
            ..small_config()
        },
    ] {
        std::fs::write(
            path.with_extension("json"),
            serde_json::to_string(&config).unwrap(),
        )
        .unwrap();
        assert!(matches!(
            Mpn::load(&path, DType::F32, &Device::Cpu),
            Err(MpnError::Checkpoint { .. })
        ));
        assert!(matches!(
            Mpn::load_trainable(&path, DType::F32, &Device::Cpu),
            Err(MpnError::Checkpoint { .. })
        ));
    }
    std::fs::write(path.with_extension("json"), "{\"latent_dim\": ").unwrap();
    assert!(matches!(
        Mpn::load(&path, DType::F32, &Device::Cpu),
        Err(MpnError::Json { .. })
    ));
    assert!(matches!(
        Mpn::load(&dir.join("missing.safetensors"), DType::F32, &Device::Cpu),
        Err(MpnError::Io { .. })
    ));
    std::fs::remove_dir_all(dir).unwrap();
}
