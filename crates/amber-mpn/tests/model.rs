//! The network as a whole: parameter count, fused vs stock-candle forward and gradients,
//! gradient coverage, input validation, checkpoints.

use amber_graph::GraphBatch;
use amber_mpn::synthetic::random_graph;
use amber_mpn::{GraphInput, Mpn, MpnConfig, MpnError};
use candle_core::{DType, Device, Tensor};
use rand::SeedableRng;
use rand::rngs::StdRng;

fn small_config() -> MpnConfig {
    MpnConfig::small(8, 3)
}

/// With the graph and the region context.
fn with_contexts(mut config: MpnConfig) -> MpnConfig {
    config.network.graph_context = true;
    config.network.region_context = true;
    config
}

/// `a` and `b` side by side, as two graphs of one batch or (`one_graph`) as one graph with two
/// components.
fn concat(a: &GraphBatch, b: &GraphBatch, one_graph: bool) -> GraphBatch {
    fn shift(v: &[u32], by: usize) -> impl Iterator<Item = u32> + '_ {
        v.iter().map(move |&x| x + by as u32)
    }
    let n = a.num_nodes + b.num_nodes;
    let mut joined = a.clone();
    joined.num_nodes = n;
    joined.num_edges += b.num_edges;
    joined.node_features.extend(&b.node_features);
    joined.edge_features.extend(&b.edge_features);
    joined.edge_src.extend(shift(&b.edge_src, a.num_nodes));
    joined.edge_dst.extend(shift(&b.edge_dst, a.num_nodes));
    joined.dst_offsets.extend(shift(&b.dst_offsets[1..], a.num_edges));
    let second = if one_graph { 0 } else { 1 };
    joined.graph_of_node.extend(std::iter::repeat_n(second, b.num_nodes));
    joined.node_offsets = if one_graph { vec![0, n as u32] } else { vec![0, a.num_nodes as u32, n as u32] };
    joined.region_of_node.extend(shift(&b.region_of_node, a.num_regions));
    joined.num_regions += b.num_regions;
    joined
}

/// A batch of two random graphs (30 and 40 nodes).
fn graph(dtype: DType, seed: u64) -> GraphInput {
    let batch = concat(&random_graph(30, 40, 4, 1, seed), &random_graph(40, 50, 4, 1, seed + 100), false);
    GraphInput::from_batch(&batch, dtype, &Device::Cpu).unwrap()
}

fn values(t: &Tensor) -> Vec<f64> {
    t.to_dtype(DType::F64).unwrap().flatten_all().unwrap().to_vec1().unwrap()
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
        m.parameters().iter().flat_map(|p| values(p)).collect::<Vec<_>>()
    };
    assert_eq!(params(1), params(1));
    assert_ne!(params(1), params(2));
}

#[test]
fn fused_forward_and_gradients_match_stock_candle() {
    for config in [small_config(), with_contexts(small_config())] {
        fused_matches_stock_candle(config);
    }
}

fn fused_matches_stock_candle(config: MpnConfig) {
    let (model, varmap) = Mpn::init(config, 3, DType::F64, &Device::Cpu).unwrap();
    let mut rng = StdRng::seed_from_u64(0);
    // A dropped graph has nodes without incoming edges, the corner case of the aggregation.
    let g = graph(DType::F64, 1).drop_edges(0.5, &mut rng).unwrap();
    let target = Tensor::rand(0.0f64, 1.0, g.num_nodes(), &Device::Cpu).unwrap();
    let fast = model.forward(&g).unwrap();
    let naive = model.forward_naive(&g).unwrap();
    for (a, b) in values(&fast).iter().zip(values(&naive)) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
    let grads = |out: &Tensor| candle_nn::loss::mse(out, &target).unwrap().backward().unwrap();
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
    let (model, varmap) = Mpn::init(with_contexts(small_config()), 0, DType::F32, &Device::Cpu).unwrap();
    let mut rng = StdRng::seed_from_u64(0);
    let loss = model.forward_train(&graph(DType::F32, 2), &mut rng).unwrap().sum_all().unwrap();
    let grads = loss.backward().unwrap();
    let vars = varmap.data().lock().unwrap();
    assert_eq!(vars.len(), model.parameters().len());
    for (name, var) in vars.iter() {
        let g = grads.get(var).unwrap_or_else(|| panic!("{name} got no gradient"));
        assert!(values(g).iter().any(|&v| v != 0.0), "{name} has an all-zero gradient");
    }
}

#[test]
fn graph_context_reaches_across_its_graph_and_no_further() {
    let (a, b) = (random_graph(30, 40, 4, 1, 1), random_graph(40, 50, 4, 1, 2));
    let mut b_changed = b.clone();
    b_changed.node_features.iter_mut().for_each(|f| *f = -*f);
    let predict = |model: &Mpn, batch: &GraphBatch| {
        let input = GraphInput::from_batch(batch, DType::F64, &Device::Cpu).unwrap();
        values(&model.forward(&input).unwrap())
    };
    let first_graph = |model: &Mpn, b: &GraphBatch, one_graph: bool| {
        predict(model, &concat(&a, b, one_graph))[..a.num_nodes].to_vec()
    };
    let (plain, _) = Mpn::init(small_config(), 1, DType::F64, &Device::Cpu).unwrap();
    let (context, _) = Mpn::init(with_contexts(small_config()), 1, DType::F64, &Device::Cpu).unwrap();
    // Without a context, a component the edges do not reach changes nothing.
    assert_eq!(first_graph(&plain, &b, true), first_graph(&plain, &b_changed, true));
    // With it, the other component of the same graph does; another graph of the batch does not.
    let (same, changed) = (first_graph(&context, &b, true), first_graph(&context, &b_changed, true));
    assert!(same.iter().zip(&changed).all(|(x, y)| (x - y).abs() > 1e-9), "{same:?} vs {changed:?}");
    assert_eq!(first_graph(&context, &b, false), first_graph(&context, &b_changed, false));
    let alone = predict(&context, &a);
    for (x, y) in alone.iter().zip(first_graph(&context, &b, false)) {
        assert!((x - y).abs() < 1e-12, "{x} alone vs {y} in a batch");
    }
}

/// Graphs without edges but self-loops: a node hears of another only through a context.
#[test]
fn region_context_reaches_across_its_region_and_no_further() {
    let batch = random_graph(40, 0, 4, 1, 3);
    assert_eq!(batch.region_of_node[10..20], [1; 10], "nodes 10..20 are region 1");
    let mut changed = batch.clone();
    changed.node_features[15 * 4..16 * 4].iter_mut().for_each(|f| *f = -*f);
    let mut config = small_config();
    config.network.region_context = true;
    let (model, _) = Mpn::init(config, 1, DType::F64, &Device::Cpu).unwrap();
    let predict = |batch: &GraphBatch| {
        values(&model.forward(&GraphInput::from_batch(batch, DType::F64, &Device::Cpu).unwrap()).unwrap())
    };
    let (before, after) = (predict(&batch), predict(&changed));
    for v in (0..40).filter(|&v| v != 15) {
        let heard = (before[v] - after[v]).abs() > 1e-9;
        assert_eq!(heard, (10..20).contains(&v), "node {v}: {} vs {}", before[v], after[v]);
    }
}

#[test]
fn f32_matches_f64() {
    let (m64, vars) = Mpn::init(small_config(), 4, DType::F64, &Device::Cpu).unwrap();
    let dir = std::env::temp_dir().join(format!("amber-mpn-f32-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("model.safetensors");
    m64.save(&vars, &path).unwrap();
    let m32 = Mpn::load(&path).unwrap();
    let (a, b) =
        (values(&m64.forward(&graph(DType::F64, 3)).unwrap()), values(&m32.forward(&graph(DType::F32, 3)).unwrap()));
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-4, "{x} vs {y}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn dropout_is_reproducible_and_only_in_training() {
    let mut config = small_config();
    config.network.edge_dropout = 0.3;
    let (model, _) = Mpn::init(config, 0, DType::F32, &Device::Cpu).unwrap();
    let g = graph(DType::F32, 4);
    let train = |seed| values(&model.forward_train(&g, &mut StdRng::seed_from_u64(seed)).unwrap());
    assert_eq!(train(7), train(7));
    assert_ne!(train(7), train(8));
    assert_eq!(values(&model.forward(&g).unwrap()), values(&model.forward(&g).unwrap()));
}

#[test]
fn wrong_feature_dimensions_are_errors() {
    let (model, _) = Mpn::init(small_config(), 0, DType::F32, &Device::Cpu).unwrap();
    let bad_nodes = GraphInput::from_batch(&random_graph(10, 10, 3, 1, 0), DType::F32, &Device::Cpu).unwrap();
    assert!(matches!(model.forward(&bad_nodes), Err(MpnError::FeatureDim { expected: 4, got: 3, .. })));
    let bad_edges = GraphInput::from_batch(&random_graph(10, 10, 4, 2, 0), DType::F32, &Device::Cpu).unwrap();
    assert!(matches!(model.forward(&bad_edges), Err(MpnError::FeatureDim { expected: 1, got: 2, .. })));
    assert!(matches!(model.forward(&graph(DType::F64, 0)), Err(MpnError::InvalidGraph(_))));
    let mut broken = random_graph(10, 10, 4, 1, 0);
    broken.edge_dst.reverse();
    assert!(matches!(model.predict(&broken), Err(MpnError::InvalidGraph(_))));
    for node_offsets in [vec![0, 5], vec![0, 0, 10], vec![0, 4, 10]] {
        // Too few nodes, an empty graph, offsets that disagree with `graph_of_node`.
        let mut split = random_graph(10, 10, 4, 1, 0);
        split.node_offsets = node_offsets;
        assert!(matches!(model.predict(&split), Err(MpnError::InvalidGraph(_))));
    }
}

#[test]
fn checkpoints_round_trip_and_reject_wrong_shapes() {
    let dir = std::env::temp_dir().join(format!("amber-mpn-ckpt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("model.safetensors");
    let (model, varmap) = Mpn::init(with_contexts(small_config()), 5, DType::F32, &Device::Cpu).unwrap();
    model.save(&varmap, &path).unwrap();
    let g = graph(DType::F32, 6);
    let expected = values(&model.forward(&g).unwrap());

    let plain = Mpn::load(&path).unwrap();
    assert!(plain.parameters().iter().all(|p| !p.is_variable()));
    let out = plain.forward(&g).unwrap();
    assert!(!out.track_op(), "inference from plain tensors must record no graph");
    assert_eq!(values(&out), expected);
    assert!(!model.for_inference().forward(&g).unwrap().track_op());
    let (trainable, vars) = Mpn::load_trainable(&path, &Device::Cpu).unwrap();
    assert_eq!(values(&trainable.forward(&g).unwrap()), expected);
    assert_eq!(vars.all_vars().len(), model.parameters().len());

    // The same weights under a configuration with another width or depth, or without contexts.
    for config in [with_contexts(MpnConfig::small(16, 3)), with_contexts(MpnConfig::small(8, 2)), small_config()] {
        std::fs::write(path.with_extension("json"), serde_json::to_string(&config).unwrap()).unwrap();
        assert!(matches!(Mpn::load(&path), Err(MpnError::Checkpoint { .. })));
        assert!(matches!(Mpn::load_trainable(&path, &Device::Cpu), Err(MpnError::Checkpoint { .. })));
    }
    std::fs::write(path.with_extension("json"), "{\"latent_dim\": ").unwrap();
    assert!(matches!(Mpn::load(&path), Err(MpnError::Json { .. })));
    assert!(matches!(Mpn::load(&dir.join("missing.safetensors")), Err(MpnError::Io { .. })));
    std::fs::remove_dir_all(dir).unwrap();
}
