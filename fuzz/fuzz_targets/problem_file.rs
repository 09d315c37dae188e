#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| amber_fuzz::problem_file(data));
