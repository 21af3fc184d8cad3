//! The C API from C: builds `examples/c/render_bowl.c` (through its pkg-config Makefile) and
//! `tests/c/error_paths.c` with the system C compiler against `include/shikki.h`, links each
//! against both `libshikki.so` and `libshikki.a`, runs them with the validation layer on, and
//! checks
//! - the example's PNG equals, byte for byte, the Rust API's PNG of the same scene
//!   (`shikki::scene::default_scene()` at the same size through `SceneRenderer`);
//! - every error path returns its status with a message (the C program checks; it exits with the
//!   number of failed checks);
//! - under valgrind (when installed), no leaks and no invalid accesses.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
use std::time::Instant;

use shikki::gpu::{ContextOptions, GpuContext};
use shikki::output::png::encode_png;
use shikki::output::PngSettings;
use shikki::scene::{default_scene, SceneRenderer};

/// Small, so that the renders (and the valgrind runs) stay fast on lavapipe.
const SIZE: u32 = 48;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// target/<profile> (the test binary lives in target/<profile>/deps), with libshikki.so and
/// libshikki.a freshly built: `cargo test` builds only what tests link (the crate has no rlib),
/// so the C libraries are built here by a nested `cargo build`, once per test binary. Cargo has
/// released the target directory's lock by the time tests run.
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
            assert_success("cargo build -p shikki-ffi --lib", &run(&mut build));
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

        let source = root.join("ffi/tests/c/error_paths.c");
        let common = |cmd: &mut Command| {
            cmd.args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-g", "-I"])
                .arg(root.join("include"))
                .arg(&source);
        };
        let mut shared = Command::new("cc");
        common(&mut shared);
        shared
            .arg("-o")
            .arg(out.join("error_paths"))
            .arg(format!("-L{}", libs.display()))
            .arg("-lshikki")
            .arg(format!("-Wl,-rpath,{}", libs.display()))
            .arg("-lm");
        assert_success("cc error_paths.c (shared)", &run(&mut shared));
        let mut fixed = Command::new("cc");
        common(&mut fixed);
        fixed
            .arg("-o")
            .arg(out.join("error_paths_static"))
            .arg(libs.join("libshikki.a"))
            .args([
                "-lgcc_s",
                "-lutil",
                "-lrt",
                "-lpthread",
                "-lm",
                "-ldl",
                "-lc",
            ]);
        assert_success("cc error_paths.c (static)", &run(&mut fixed));
        Programs { out }
    }

    fn command(&self, program: &str) -> Command {
        let mut command = Command::new(self.out.join(program));
        command.current_dir(&self.out).env("SHIKKI_VALIDATION", "1");
        command
    }
}

/// What the Rust API renders for the scene render_bowl.c renders: the default scene at
/// SIZE × SIZE with 1 sample, PNG at 0 EV with ACES.
fn rust_png() -> Vec<u8> {
    let gpu = GpuContext::new(&ContextOptions {
        validation: true,
        ..ContextOptions::default()
    })
    .expect("a Vulkan device");
    let mut scene = default_scene();
    scene.output.width = SIZE;
    scene.output.height = SIZE;
    scene.output.samples = 1;
    let image = SceneRenderer::new(&gpu)
        .and_then(|mut renderer| renderer.render(&gpu, &scene))
        .expect("the Rust API renders the default scene");
    encode_png(&image, &PngSettings::default()).expect("PNG encoding")
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
        if actual != expected {
            let keep = repo_root().join(format!("target/test-output/{program}-actual.png"));
            let _ = std::fs::create_dir_all(keep.parent().unwrap_or(Path::new(".")));
            let _ = std::fs::write(&keep, &actual);
            let _ = std::fs::write(
                keep.with_file_name(format!("{program}-expected.png")),
                &expected,
            );
            panic!(
                "{program}'s PNG ({} bytes) differs from the Rust API's ({} bytes); kept at {}",
                actual.len(),
                expected.len(),
                keep.display()
            );
        }
    }
}

#[test]
fn c_error_paths_return_their_status_and_a_message_shared_and_static() {
    let programs = Programs::get();
    for program in ["error_paths", "error_paths_static"] {
        let output = run(&mut programs.command(program));
        assert_success(program, &output);
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(
            stdout.lines().any(|l| l.ends_with("checks, 0 failed")),
            "{program} did not finish its checks:\n{stdout}"
        );
    }
}

fn valgrind_available() -> bool {
    Command::new("valgrind")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// valgrind on the C programs: no leak, no invalid access (suppressions only for code that is not
/// shikki's, each explained in tests/valgrind.supp). The validation layer is off here: it is
/// checked by the tests above, and under valgrind it would multiply the run time.
#[test]
fn c_programs_are_valgrind_clean() {
    if !valgrind_available() {
        eprintln!("valgrind is not installed (scripts/setup installs it); skipping");
        return;
    }
    let programs = Programs::get();
    let suppressions = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/valgrind.supp");
    let valgrind = |args: &[&str]| {
        let mut command = Command::new("valgrind");
        command
            .current_dir(&programs.out)
            .env_remove("SHIKKI_VALIDATION")
            .args([
                "--leak-check=full",
                "--error-exitcode=1",
                "--errors-for-leak-kinds=definite,indirect,possible",
                "--keep-debuginfo=yes",
                // Deep enough that a suppressed driver stack is seen whole.
                "--num-callers=40",
            ])
            .arg(format!("--suppressions={}", suppressions.display()))
            .args(args);
        run(&mut command)
    };
    let output = valgrind(&[programs
        .out
        .join("error_paths")
        .to_str()
        .unwrap_or_default()]);
    assert_success("valgrind error_paths", &output);
}
