//! `shikki render SCENE.toml` with `--set` scene-path overrides, end to end (validated Vulkan).

use std::path::Path;
use std::process::Command;

#[test]
fn scene_file_with_set_overrides_renders_what_the_overrides_say() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_shikki"))
        .env("SHIKKI_PIPELINE_CACHE", "0")
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
    // Only the light towards (1, 1, 1) is left on. Pixel (14, 16)'s ray hits the sphere at
    // ≈ (-0.550, -0.450, 0.704) (hand ray-cast: fov 40°, aspect 40/24, eye at z = 4), where
    // N·L ≈ -0.17 < 0: no light at all, radiance exactly 0. With the second light on it is lit.
    let shadowed = image.get(14, 16);
    assert_eq!(shadowed[3], 1.0);
    assert_eq!(shadowed[..3], [0.0; 3], "{shadowed:?}");
}
