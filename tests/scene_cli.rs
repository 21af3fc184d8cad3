//! `shikki render SCENE.toml` with `--set` scene-path overrides, end to end (validated Vulkan).

use std::path::Path;
use std::process::Command;

#[test]
fn scene_file_with_set_overrides_renders_what_the_overrides_say() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_shikki"))
        .arg("render")
        .arg(&scene)
        .args([
            "--set",
            "output.size=40x24",
            "--set",
            "output.samples=1",
            "--set",
            "output.format=exr",
            "--set",
            "light.1.irradiance=0",
        ])
        .current_dir(dir.path())
        .env("SHIKKI_VALIDATION", "1")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // format = exr and no -o: shikki.exr, at the overridden size, transparent background.
    let bytes = std::fs::read(dir.path().join("shikki.exr")).unwrap();
    let image = shikki::output::exr::decode_exr(&bytes).unwrap();
    assert_eq!((image.width, image.height), (40, 24));
    assert_eq!(image.get(0, 0), [0.0; 4]);
    assert_eq!(image.get(20, 12)[3], 1.0);
    // Only the light towards (1, 1, 1) is left on, so the lower-left of the sphere (facing
    // away from it, towards (-1, -1, ·)) gets no light at all: radiance exactly 0 there.
    let shadowed = image.get(15, 15);
    assert_eq!(shadowed[3], 1.0);
    assert_eq!(shadowed[..3], [0.0; 3], "{shadowed:?}");
}
