#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| amber_fuzz::model_dir(data));
