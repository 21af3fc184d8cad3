//! Links Debian's static glslang and SPIRV-Tools archives into whoever uses this crate.
//!
//! Debian's `libshaderc.so` has undefined glslang symbols that rust-lld rejects (see
//! shared/NOTES.md). `shaderc`'s `prefer-static-linking` picks `libshaderc_combined.a`, which on
//! Debian still needs glslang and SPIRV-Tools from their own archives. Link directives printed by a
//! top-level build.rs do not reach that build script's own link step; printed from a dependency
//! of it (this crate), they do.

fn main() {
    let search = std::env::var("SHADERC_LIB_DIR")
        .unwrap_or_else(|_| "/usr/lib/x86_64-linux-gnu".to_string());
    println!("cargo:rustc-link-search=native={search}");
    for lib in [
        "glslang",
        "MachineIndependent",
        "GenericCodeGen",
        "OSDependent",
        "OGLCompiler",
        "HLSL",
        "SPIRV",
        "SPIRV-Tools-opt",
        "SPIRV-Tools",
        "glslang-default-resource-limits",
    ] {
        println!("cargo:rustc-link-lib=static={lib}");
    }
    println!("cargo:rustc-link-lib=dylib=stdc++");
    println!("cargo:rerun-if-env-changed=SHADERC_LIB_DIR");
}
