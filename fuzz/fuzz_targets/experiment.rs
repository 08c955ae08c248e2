//! The experiment file (TOML) parser and its checks on arbitrary text.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = tempera_cli::experiment::config::Config::parse(&text, Path::new("fuzz/experiment.toml"));
});
