//! `include/shikki.h` must be exactly what the pinned cbindgen generates from `ffi/src` with
//! `ffi/cbindgen.toml`; this test fails when someone changes the API and forgets the header.
//! `SHIKKI_BLESS_HEADER=1` rewrites the header instead of comparing.

use std::path::Path;

#[test]
fn checked_in_header_matches_a_fresh_generation() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let header_path = crate_dir.join("../include/shikki.h");
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("ffi/cbindgen.toml parses");
    // Parsing the crate's own sources only (no `cargo metadata`, no network): the API is in
    // ffi/src and every type it exposes is defined there.
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(crate_dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen generates the header");
    let mut fresh = Vec::new();
    bindings.write(&mut fresh);
    let fresh = String::from_utf8(fresh).expect("the header is UTF-8");

    if std::env::var("SHIKKI_BLESS_HEADER").is_ok_and(|v| v == "1") {
        std::fs::write(&header_path, &fresh).expect("write include/shikki.h");
        return;
    }
    let checked_in = std::fs::read_to_string(&header_path).unwrap_or_default();
    if checked_in != fresh {
        let first_difference = checked_in
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .map_or_else(
                || "one is a prefix of the other".to_string(),
                |i| format!("first at line {}", i + 1),
            );
        panic!(
            "include/shikki.h is stale ({first_difference}); regenerate it with \
             `SHIKKI_BLESS_HEADER=1 cargo test -p shikki-ffi --test header` and commit it"
        );
    }
}
