//! The C API from C: builds `examples/c/render_bowl.c` (through its pkg-config Makefile) and the
//! programs of `tests/c/` with the system C compiler against `include/shikki.h`, runs them with
//! the validation layer on, and checks
//! - the example's PNG equals, byte for byte, the Rust API's PNG of the same scene
//!   (`shikki::scene::default_scene()` at the same size through `SceneRenderer`), shared and
//!   static;
//! - `error_paths.c`: every error path returns its status with a message, hostile handles
//!   (destroyed, stale, forged, wrong kind), NULL out-pointers, bad UTF-8 and huge sizes
//!   included (the C program checks; it exits with the number of failed checks), shared and
//!   static;
//! - `threads.c`: the thread-safety contract of docs/c-api.md;
//! - `environment_model.c`: `shikki_scene_set_environment_model` — BRDF renders differently from
//!   PAPER, the scene TOML's `[render] environment_model` reaches the handle, an unknown model
//!   number is refused with a message naming the valid ones;
//! - `light_transport.c`: `shikki_scene_set_light_transport` — shadows on by default, off by the
//!   call or the scene TOML, and ray tracing off giving the image without shadows;
//! - `large_environment.c`: an 8192 × 4096 HDRI (written here) renders through the C API as it
//!   does through the CLI, to the bytes of the Rust API's render; the environment disk cache and
//!   the warning callback;
//! - with `SHIKKI_VALGRIND_EXAMPLE=1` (CI): both programs under valgrind's memcheck (no invalid
//!   access, no leak) and under AddressSanitizer + UndefinedBehaviorSanitizer.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
use std::time::Instant;

use shikki::environment::load_environment;
use shikki::gpu::{ContextOptions, GpuContext};
use shikki::output::exr::encode_exr;
use shikki::output::png::encode_png;
use shikki::output::{HdrImage, PngSettings};
use shikki::scene::{default_scene, EnvironmentSpec, Scene, SceneRenderer};

/// Small, so that the renders (and the valgrind runs) stay fast on lavapipe.
const SIZE: u32 = 48;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// target/<profile> (the test binary lives in target/<profile>/deps), with libshikki.so and
/// libshikki.a freshly built: `cargo test` builds only what tests link (the crate has no rlib),
/// so the C libraries are built here by a nested `cargo build`, once per test binary. Cargo has
/// released the target directory's lock by the time tests run. It only links the C library:
/// ffi/Cargo.toml and the dev profile keep its other units the test build's, and it fails if it
/// compiled any of them again (BENCHMARKS.md "CI's time").
fn library_dir() -> PathBuf {
    static BUILT: OnceLock<PathBuf> = OnceLock::new();
    BUILT
        .get_or_init(|| {
            let exe = std::env::current_exe().expect("test executable path");
            let dir = exe
                .parent()
                .and_then(Path::parent)
                .expect("target/<profile>/deps/<test>")
                .to_path_buf();
            let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
            let mut build = Command::new(cargo);
            build.args(["build", "-p", "shikki-ffi", "--lib"]);
            if dir.file_name().is_some_and(|name| name == "release") {
                build.arg("--release");
            }
            let output = run(&mut build);
            assert_success("cargo build -p shikki-ffi --lib", &output);
            let again = compiled_again(&String::from_utf8_lossy(&output.stderr));
            assert!(
                again.is_empty(),
                "the nested `cargo build -p shikki-ffi --lib` compiled {again:?} again: its \
                 features or profiles differ from the test build's (compare `cargo test \
                 --workspace --no-run --unit-graph` with its own `--unit-graph`, BENCHMARKS.md \
                 \"CI's time\"), or the sources changed since the test build"
            );
            for lib in ["libshikki.so", "libshikki.a"] {
                assert!(
                    dir.join(lib).is_file(),
                    "{} is missing",
                    dir.join(lib).display()
                );
            }
            dir
        })
        .clone()
}

#[test]
fn the_nested_build_check_names_what_was_compiled_again() {
    let stderr = "   Compiling serde v1.0.229\n   Compiling shikki v0.1.0 (/r)\n   Compiling \
                  shikki-ffi v0.1.0 (/r/ffi)\n    Finished `dev` profile in 9.1s\n";
    assert_eq!(
        compiled_again(stderr),
        ["serde v1.0.229", "shikki v0.1.0 (/r)"]
    );
    let links = "   Compiling shikki-ffi v0.1.0 (/r/ffi)\n    Finished `dev` profile in 3.5s\n";
    assert!(compiled_again(links).is_empty());
}

/// The crates other than the C library itself that a cargo build's stderr says it compiled.
fn compiled_again(stderr: &str) -> Vec<String> {
    stderr
        .lines()
        .filter_map(|line| line.trim_start().strip_prefix("Compiling "))
        .filter(|krate| !krate.starts_with("shikki-ffi "))
        .map(str::to_owned)
        .collect()
}

fn run(command: &mut Command) -> Output {
    let started = Instant::now();
    let output = command
        .output()
        .unwrap_or_else(|e| panic!("cannot run {command:?}: {e}"));
    eprintln!(
        "{command:?}: {:.1} s, {}",
        started.elapsed().as_secs_f64(),
        output.status
    );
    output
}

fn assert_success(what: &str, output: &Output) {
    assert!(
        output.status.success(),
        "{what} failed ({}):\n--- stdout\n{}\n--- stderr\n{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
}

/// How a C test program is compiled: against the shared or the static library, and whether with
/// AddressSanitizer + UndefinedBehaviorSanitizer on the C side.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Link {
    Shared,
    Static,
    SharedSanitized,
}

/// The C programs, built once per test binary into target/<profile>/c-api.
struct Programs {
    out: PathBuf,
}

impl Programs {
    fn get() -> &'static Programs {
        static PROGRAMS: OnceLock<Programs> = OnceLock::new();
        PROGRAMS.get_or_init(Programs::build)
    }

    fn build() -> Self {
        let root = repo_root();
        let libs = library_dir();
        let out = libs.join("c-api");
        // Stale programs or images from an earlier run must not pass for this run's.
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(&out).expect("create target/<profile>/c-api");
        let make = run(Command::new("make")
            .arg("-C")
            .arg(root.join("examples/c"))
            .arg(format!("ROOT={}", root.display()))
            .arg(format!("LIBDIR={}", libs.display()))
            .arg(format!("OUT={}", out.display())));
        assert_success("make -C examples/c", &make);
        let programs = Programs { out };
        programs.compile("error_paths", "error_paths", Link::Shared);
        programs.compile("error_paths", "error_paths_static", Link::Static);
        programs.compile("threads", "threads", Link::Shared);
        programs.compile("large_environment", "large_environment", Link::Shared);
        programs.compile("environment_model", "environment_model", Link::Shared);
        programs.compile("light_transport", "light_transport", Link::Shared);
        programs.compile("mesh_notes", "mesh_notes", Link::Shared);
        if slow_checks_enabled() {
            programs.compile("error_paths", "error_paths_asan", Link::SharedSanitized);
            programs.compile("threads", "threads_asan", Link::SharedSanitized);
        }
        programs
    }

    /// Compiles `ffi/tests/c/<source>.c` into `<out>/<program>`.
    fn compile(&self, source: &str, program: &str, link: Link) {
        let root = repo_root();
        let libs = library_dir();
        let mut cc = Command::new("cc");
        cc.args([
            "-std=c11", "-Wall", "-Wextra", "-Werror", "-g", "-pthread", "-I",
        ])
        .arg(root.join("include"));
        if link == Link::SharedSanitized {
            // Only the C side is instrumented (the Rust library would need a nightly compiler
            // and a rebuilt standard library); ASan still checks every C access to memory the
            // library hands out or fills, and LeakSanitizer sees every allocation, the
            // library's included, since malloc is intercepted process-wide.
            cc.args([
                "-fsanitize=address,undefined",
                "-fno-sanitize-recover=all",
                "-fno-omit-frame-pointer",
            ]);
        }
        cc.arg(root.join(format!("ffi/tests/c/{source}.c")))
            .arg("-o")
            .arg(self.out.join(program));
        if link == Link::Static {
            cc.arg(libs.join("libshikki.a")).args([
                "-lgcc_s",
                "-lutil",
                "-lrt",
                "-lpthread",
                "-lm",
                "-ldl",
                "-lc",
            ]);
        } else {
            cc.arg(format!("-L{}", libs.display()))
                .arg("-lshikki")
                .arg(format!("-Wl,-rpath,{}", libs.display()))
                .arg("-lm");
        }
        assert_success(&format!("cc {source}.c -o {program}"), &run(&mut cc));
    }

    fn command(&self, program: &str) -> Command {
        let mut command = Command::new(self.out.join(program));
        command.current_dir(&self.out).env("SHIKKI_VALIDATION", "1");
        command
    }

    fn path(&self, program: &str) -> String {
        self.out.join(program).display().to_string()
    }
}

/// The C program finished every check and none failed (it prints "<n> checks, 0 failed" last
/// and exits with the number of failures).
fn assert_all_checks_passed(program: &str, output: &Output) {
    assert_success(program, output);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.lines().any(|l| l.ends_with("checks, 0 failed")),
        "{program} did not finish its checks:\n{stdout}"
    );
    for line in stdout.lines().filter(|l| l.starts_with("info ")) {
        eprintln!("{program}: {line}");
    }
}

/// The default scene at SIZE × SIZE with 1 sample: what the C programs render.
fn small_default_scene() -> Scene {
    let mut scene = default_scene();
    scene.output.width = SIZE;
    scene.output.height = SIZE;
    scene.output.samples = 1;
    scene
}

/// `scene` rendered by the Rust API (validation on, no disk cache) and encoded with `png`.
fn rust_render_png(scene: &Scene, png: &PngSettings) -> Vec<u8> {
    let gpu = GpuContext::new(&ContextOptions {
        validation: true,
        ..ContextOptions::default()
    })
    .expect("a Vulkan device");
    let image = SceneRenderer::with_disk_cache(None)
        .render(&gpu, scene)
        .expect("the Rust API renders the scene");
    encode_png(&image, png).expect("PNG encoding")
}

/// What the Rust API renders for the scene render_bowl.c renders: the default scene at
/// SIZE × SIZE with 1 sample, PNG at 0 EV with ACES.
fn rust_png() -> Vec<u8> {
    rust_render_png(&small_default_scene(), &PngSettings::default())
}

/// Keeps `actual` and `expected` under target/test-output and fails, when they differ.
fn assert_same_png(program: &str, actual: &[u8], expected: &[u8]) {
    if actual == expected {
        return;
    }
    let keep = repo_root().join(format!("target/test-output/{program}-actual.png"));
    let _ = std::fs::create_dir_all(keep.parent().unwrap_or(Path::new(".")));
    let _ = std::fs::write(&keep, actual);
    let _ = std::fs::write(
        keep.with_file_name(format!("{program}-expected.png")),
        expected,
    );
    panic!(
        "{program}'s PNG ({} bytes) differs from the Rust API's ({} bytes); kept at {}",
        actual.len(),
        expected.len(),
        keep.display()
    );
}

#[test]
fn c_example_png_equals_the_rust_api_png_shared_and_static() {
    let programs = Programs::get();
    let expected = rust_png();
    for program in ["render_bowl", "render_bowl_static"] {
        let png = programs.out.join(format!("{program}.png"));
        let output = run(programs.command(program).arg(&png).arg(SIZE.to_string()));
        assert_success(program, &output);
        let actual = std::fs::read(&png).expect("the example wrote its PNG");
        assert_same_png(program, &actual, &expected);
    }
}

#[test]
fn c_error_paths_return_their_status_and_a_message_shared_and_static() {
    let programs = Programs::get();
    for program in ["error_paths", "error_paths_static"] {
        let output = run(&mut programs.command(program));
        assert_all_checks_passed(program, &output);
    }
}

/// The thread-safety contract of docs/c-api.md: renders on parallel renderers and on one shared
/// renderer equal the single-threaded bytes, a render never mixes two output sizes, last errors
/// stay on their thread, handles may be destroyed while another thread uses them.
#[test]
fn c_threads_render_identical_images_and_keep_their_errors_apart() {
    let programs = Programs::get();
    let output = run(&mut programs.command("threads"));
    assert_all_checks_passed("threads", &output);
}

/// Shadows from C: on by default, a shadow on the board under a sphere, none with
/// `shikki_scene_set_light_transport(scene, 0, 1)`, the same bytes with ray tracing off, and the
/// scene TOML's `[render] shadows` reaching the handle.
#[test]
fn c_light_transport_switches_shadows() {
    let programs = Programs::get();
    let output = run(&mut programs.command("light_transport"));
    assert_all_checks_passed("light_transport", &output);
}

/// What the mesh loader changed in a file reaches C through the renderer's warning callback, once
/// per renderer and file, for `shikki_mesh_load` and for a scene TOML's mesh file (both were
/// dropped: the C API turned each into an in-memory mesh with no notes); a mesh from arrays says
/// nothing.
#[test]
fn c_mesh_load_notes_reach_the_warning_callback() {
    let programs = Programs::get();
    let output = run(&mut programs.command("mesh_notes"));
    assert_all_checks_passed("mesh_notes", &output);
}

/// The environment model from C: `SHIKKI_ENV_MODEL_BRDF` renders a 32 × 32 sphere differently
/// from `SHIKKI_ENV_MODEL_PAPER` (and switching back gives PAPER's bytes again), a scene TOML's
/// `[render] environment_model = "brdf"` renders like the call-built BRDF scene, and an unknown
/// model number is `INVALID_ARGUMENT` naming the valid values, leaving the scene unchanged.
#[test]
fn c_environment_model_brdf_differs_from_paper_and_bad_numbers_are_refused() {
    let programs = Programs::get();
    let output = run(&mut programs.command("environment_model"));
    assert_all_checks_passed("environment_model", &output);
}

/// The built-in studio map upsampled 8× by pixel replication to 8192 × 4096 and written as a
/// run-length-encoded Radiance file (runs of 8 equal bytes keep it near 32 MiB).
fn write_large_hdr(path: &Path) {
    const FACTOR: usize = 8;
    let studio = load_environment("builtin:studio")
        .expect("the built-in studio map")
        .image;
    let (w, h) = (
        studio.width as usize * FACTOR,
        studio.height as usize * FACTOR,
    );
    let mut bytes = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes();
    let mut channel = vec![0u8; w];
    for y in 0..h {
        let row = &studio.pixels[(y / FACTOR) * studio.width as usize..];
        let rgbe: Vec<[u8; 4]> = (0..w).map(|x| to_rgbe(row[x / FACTOR])).collect();
        bytes.extend_from_slice(&[2, 2, (w >> 8) as u8, (w & 0xff) as u8]);
        for c in 0..4 {
            for (byte, pixel) in channel.iter_mut().zip(&rgbe) {
                *byte = pixel[c];
            }
            rle_channel(&channel, &mut bytes);
        }
    }
    std::fs::write(path, bytes).expect("write the large map");
}

/// Radiance's shared-exponent encoding: mantissas = channel · 256 / 2^e, with e such that the
/// largest channel lies in [0.5, 1) · 2^e.
fn to_rgbe([r, g, b]: [f32; 3]) -> [u8; 4] {
    let largest = r.max(g).max(b);
    if largest < 1e-32 {
        return [0; 4];
    }
    let exponent = largest.log2().floor() as i32 + 1;
    let scale = 256.0 / 2f32.powi(exponent);
    let m = |c: f32| (c * scale) as u8;
    [m(r), m(g), m(b), (exponent + 128) as u8]
}

/// One channel of a scanline: runs of 4 to 127 equal bytes as (128 + n, byte), the rest as
/// literals of up to 128 bytes (n, bytes…).
fn rle_channel(data: &[u8], out: &mut Vec<u8>) {
    let run_at = |i: usize| {
        let limit = (data.len() - i).min(127);
        (1..limit).take_while(|&k| data[i + k] == data[i]).count() + 1
    };
    let mut i = 0;
    while i < data.len() {
        let run = run_at(i);
        if run >= 4 {
            out.extend_from_slice(&[128 + run as u8, data[i]]);
            i += run;
            continue;
        }
        let start = i;
        while i < data.len() && i - start < 128 && run_at(i) < 4 {
            i += 1;
        }
        out.push((i - start) as u8);
        out.extend_from_slice(&data[start..i]);
    }
}

/// A small linear EXR whose first column is negative: replaced by 0 on load, with a warning.
fn write_bad_pixel_exr(path: &Path) {
    let (w, h) = (64, 32);
    let pixels = (0..w * h)
        .map(|i| {
            if i % w == 0 {
                [-1.0, 0.5, 0.5, 1.0]
            } else {
                [0.8, 0.6, 0.4, 1.0]
            }
        })
        .collect();
    let image = HdrImage {
        width: w,
        height: h,
        pixels,
    };
    std::fs::write(path, encode_exr(&image).expect("EXR encoding")).expect("write the EXR");
}

/// An 8192 × 4096 HDRI renders through the C API as through the CLI (prefilter face clamped to
/// the device, so lavapipe takes it), byte for byte the Rust API's PNG; the disk cache and the
/// warning callback are checked by the program. On lavapipe each 8K prefilter takes seconds, so
/// the test renders the map twice (C, then Rust) and the C program's second renderer reads the
/// disk cache instead.
#[test]
fn c_renders_an_8k_environment_like_the_rust_api() {
    let programs = Programs::get();
    let dir = std::env::temp_dir().join(format!("shikki-large-env-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create the temporary directory");
    let (large, bad) = (dir.join("large.hdr"), dir.join("bad-pixels.exr"));
    let started = Instant::now();
    write_large_hdr(&large);
    write_bad_pixel_exr(&bad);
    eprintln!("maps written: {:.1} s", started.elapsed().as_secs_f64());
    let png = dir.join("large.png");
    let output = run(programs
        .command("large_environment")
        .arg(&large)
        .arg(&bad)
        .arg(dir.join("cache"))
        .arg(&png)
        .arg(SIZE.to_string()));
    assert_all_checks_passed("large_environment", &output);
    let actual = std::fs::read(&png).expect("the program wrote its PNG");

    let mut scene = small_default_scene();
    scene.environment = EnvironmentSpec::named(large.display().to_string());
    let display = PngSettings {
        exposure_ev: scene.output.exposure_ev,
        tone_curve: scene.output.tone_curve,
    };
    let started = Instant::now();
    let expected = rust_render_png(&scene, &display);
    eprintln!(
        "Rust API render with the large map: {:.1} s",
        started.elapsed().as_secs_f64()
    );
    let _ = std::fs::remove_dir_all(&dir);
    assert_same_png("large_environment", &actual, &expected);
}

/// The slow runs (valgrind, helgrind, sanitizers: minutes on lavapipe) happen when
/// `SHIKKI_VALGRIND_EXAMPLE=1`, which CI sets (.ci/run); a plain `cargo test` stays quick. When
/// they are asked for, a missing tool is a failure, not a skip.
fn slow_checks_enabled() -> bool {
    std::env::var("SHIKKI_VALGRIND_EXAMPLE").is_ok_and(|v| v == "1")
}

fn skip_slow(what: &str) -> bool {
    if slow_checks_enabled() {
        return false;
    }
    eprintln!("{what}: skipped; set SHIKKI_VALGRIND_EXAMPLE=1 to run it (CI does)");
    true
}

fn require_valgrind() {
    let version = Command::new("valgrind").arg("--version").output();
    assert!(
        version.is_ok_and(|o| o.status.success()),
        "SHIKKI_VALGRIND_EXAMPLE=1 but valgrind is not installed: run scripts/setup (or apt-get \
         install valgrind)"
    );
}

/// valgrind with the suppressions of tests/valgrind.supp (only code that is not shikki's, each
/// explained there). The validation layer is off here: it is checked by the native runs, and
/// under valgrind it would multiply the run time. Nor does lavapipe optimise its shaders here
/// (`GALLIVM_PERF=nopt`): on a fresh machine (CI's) Mesa's shader cache is empty and LLVM's
/// passes over each pipeline, run under valgrind, were most of the time (BENCHMARKS.md "CI's
/// time"); a native run does not warm the cache for valgrind (llvmpipe keys it by the CPU
/// features valgrind hides). The passes are Mesa's code, not shikki's: memcheck still sees every
/// call of the library.
fn valgrind(programs: &Programs, tool_args: &[&str], program: &str) -> Output {
    let suppressions = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/valgrind.supp");
    let mut command = Command::new("valgrind");
    command
        .current_dir(&programs.out)
        .env_remove("SHIKKI_VALIDATION")
        .env("GALLIVM_PERF", "nopt")
        .args([
            "--error-exitcode=1",
            "--keep-debuginfo=yes",
            "--num-callers=40",
        ])
        .arg(format!("--suppressions={}", suppressions.display()))
        .args(tool_args)
        .arg(programs.path(program));
    run(&mut command)
}

const MEMCHECK: &[&str] = &[
    "--leak-check=full",
    "--errors-for-leak-kinds=definite,indirect,possible",
];

/// memcheck on the error paths: no invalid access, no leak (every hostile call included).
#[test]
fn c_error_paths_are_valgrind_clean() {
    if skip_slow("valgrind error_paths") {
        return;
    }
    require_valgrind();
    let programs = Programs::get();
    let output = valgrind(programs, MEMCHECK, "error_paths");
    assert_all_checks_passed("valgrind error_paths", &output);
}

/// memcheck on the threaded program: no invalid access or leak across threads, including the
/// renderer freed on the thread whose render outlived its destroy.
#[test]
fn c_threads_are_valgrind_clean() {
    if skip_slow("valgrind threads") {
        return;
    }
    require_valgrind();
    let programs = Programs::get();
    let output = valgrind(programs, MEMCHECK, "threads");
    assert_all_checks_passed("valgrind threads", &output);
}

/// The ICD library lavapipe is loaded from (from its Vulkan ICD manifest), for the sanitizer run.
/// The manifest is `VK_DRIVER_FILES` when set, else the first `lvp_icd*.json` in the loader's
/// system directories (Mesa ≥ 24 installs `lvp_icd.json`, older ones `lvp_icd.<arch>.json`).
fn lavapipe_library() -> PathBuf {
    let manifest = std::env::var_os("VK_DRIVER_FILES")
        .map(PathBuf::from)
        .or_else(find_lavapipe_manifest)
        .expect("no lavapipe ICD manifest (lvp_icd*.json) in /usr/share/vulkan/icd.d or /etc/vulkan/icd.d");
    let text = std::fs::read_to_string(&manifest)
        .unwrap_or_else(|e| panic!("cannot read the lavapipe ICD manifest {manifest:?}: {e}"));
    // "library_path": "<path>" — the one string field needed, without a JSON dependency.
    let path = text
        .split("\"library_path\"")
        .nth(1)
        .and_then(|rest| rest.split('"').nth(1))
        .unwrap_or_else(|| panic!("{manifest:?} has no library_path"));
    // The loader's rules: a bare file name is found by the dynamic linker's search (as LD_PRELOAD
    // finds it too), a relative path with a slash is relative to the manifest's directory.
    let path = PathBuf::from(path);
    if path.is_absolute() || path.components().count() == 1 {
        path
    } else {
        manifest.parent().unwrap_or(Path::new("/")).join(path)
    }
}

fn find_lavapipe_manifest() -> Option<PathBuf> {
    ["/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d"]
        .iter()
        .filter_map(|dir| std::fs::read_dir(dir).ok())
        .flat_map(|entries| entries.filter_map(|e| e.ok()).map(|e| e.path()))
        .find(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("lvp_icd") && n.ends_with(".json"))
        })
}

/// AddressSanitizer + UndefinedBehaviorSanitizer (+ LeakSanitizer) on both programs.
///
/// lavapipe is preloaded so that it stays mapped until LeakSanitizer runs at exit: the Vulkan
/// loader `dlclose`s it, after which the driver's own never-freed worker-thread allocations
/// (the ones tests/valgrind.supp names) lose the global that points at them and are reported
/// as leaks in an "<unknown module>". Kept mapped, they are reachable; nothing else needs a
/// suppression. (valgrind above runs without the preload, so a leak of ours still fails it.)
#[test]
fn c_programs_are_asan_and_ubsan_clean() {
    if skip_slow("ASan+UBSan") {
        return;
    }
    let programs = Programs::get();
    let asan = Command::new("cc")
        .arg("-print-file-name=libasan.so")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .expect("cc -print-file-name=libasan.so");
    for program in ["error_paths_asan", "threads_asan"] {
        let mut command = programs.command(program);
        command
            .env_remove("SHIKKI_VALIDATION")
            // The sanitizer runtime must come first among the preloads.
            .env(
                "LD_PRELOAD",
                format!("{asan} {}", lavapipe_library().display()),
            )
            .env(
                "ASAN_OPTIONS",
                "detect_leaks=1:halt_on_error=1:detect_stack_use_after_return=1",
            )
            .env("UBSAN_OPTIONS", "halt_on_error=1:print_stacktrace=1");
        let output = run(&mut command);
        assert_all_checks_passed(program, &output);
    }
}
