#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| amber_fuzz::training_config(data));
