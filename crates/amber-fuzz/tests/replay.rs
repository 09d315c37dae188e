//! Replays the fuzz corpus (`fuzz/corpus/<target>/`: the seeds, the inputs that once crashed or
//! misled amber, and what libFuzzer kept as new coverage) through every target on stable Rust, so
//! CI keeps each of them fixed without a fuzzer.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

#[test]
fn every_corpus_input_keeps_the_promises_of_its_target() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus");
    let mut failures = Vec::new();
    for (name, target) in amber_fuzz::TARGETS {
        let dir = corpus.join(name);
        let mut inputs: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|entry| entry.unwrap().path())
            .collect();
        inputs.sort();
        assert!(inputs.len() >= 5, "{}: only {} inputs", dir.display(), inputs.len());
        for input in inputs {
            let data = std::fs::read(&input).unwrap();
            if let Err(panic) = catch_unwind(AssertUnwindSafe(|| target(&data))) {
                let message = panic.downcast_ref::<String>().cloned().unwrap_or_else(|| format!("{panic:?}"));
                failures.push(format!("{}: {message}", input.display()));
            }
        }
    }
    assert!(failures.is_empty(), "{} inputs broke a promise:\n{}", failures.len(), failures.join("\n"));
}
