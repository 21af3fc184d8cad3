//! The human-readable form of a [`BenchReport`]: a Markdown table (pasted into BENCHMARKS.md).

use super::{BenchReport, Stat};

fn ms(s: &Stat) -> String {
    format!("{:.1} ms", s.median * 1e3)
}

fn spread(s: &Stat) -> String {
    format!("{:.1}–{:.1}", s.min * 1e3, s.max * 1e3)
}

/// The report as Markdown: machine, driver, one row per figure, then the targets.
pub fn markdown(report: &BenchReport) -> String {
    let r = report;
    let mut out = format!(
        "shikki {} ({} build), {} runs per figure after a warm-up\n\n\
         - machine: {} ({} cores, {})\n\
         - driver: {} — {} {} (Vulkan {})\n\n\
         | stage | figure | median | min–max (ms) |\n|---|---|---|---|\n",
        r.shikki_version,
        r.build_profile,
        r.config.runs,
        r.machine.cpu_model,
        r.machine.cores,
        r.machine.os,
        r.driver.device,
        r.driver.driver_name,
        r.driver.driver_info,
        r.driver.vulkan,
    );
    let mut row = |stage: &str, figure: String, s: &Stat| {
        out.push_str(&format!(
            "| {stage} | {figure} | {} | {} |\n",
            ms(s),
            spread(s)
        ));
    };
    if let Some(render) = &r.render {
        let name = format!(
            "bowl {} tris, {}², {}× MSAA, env + {} lights",
            render.triangles, render.width, render.samples, render.lights
        );
        row(
            "render",
            format!("{name}: lacquer mesh pass (GPU)"),
            &render.lacquer_gpu,
        );
        row(
            "render",
            "same, trivial.frag mesh pass (GPU)".into(),
            &render.trivial_gpu,
        );
        row(
            "render",
            "lacquer render call (wall)".into(),
            &render.lacquer_wall,
        );
        row(
            "render",
            "copy-out to readback (GPU)".into(),
            &render.copy_out_gpu,
        );
        let m = &render.models;
        row(
            "render",
            format!(
                "default scene {}², `paper` environment model (GPU)",
                m.width
            ),
            &m.paper_gpu,
        );
        row(
            "render",
            "same, `brdf` environment model (GPU)".into(),
            &m.brdf_gpu,
        );
    }
    if let Some(p) = &r.prefilter {
        row(
            "prefilter",
            format!(
                "face {}, K = {} + irradiance: GPU (wall)",
                p.face_size, p.layers
            ),
            &p.gpu_wall,
        );
        let passes = if p.timestamps_late {
            "GPU passes (timestamps; one pass late on this driver: late_timestamps_after_graphics)"
        } else {
            "GPU passes (timestamps)"
        };
        row("prefilter", passes.into(), &p.gpu_passes);
        row(
            "prefilter",
            format!("CPU oracle, {} threads (wall)", p.cpu_threads),
            &p.cpu_oracle,
        );
    }
    let mut derived = String::new();
    if let Some(b) = &r.batch {
        row(
            "batch",
            format!("{} jobs at {}² → PNG, whole run (wall)", b.jobs, b.width),
            &b.run_wall,
        );
        row(
            "batch",
            "GPU time per image (timestamps)".into(),
            &b.gpu_per_image,
        );
        derived.push_str(&format!(
            "| batch images / s (median) | {:.2} |\n\
             | batch GPU ceiling, images / s | {:.2} |\n",
            b.images_per_second.median, b.gpu_ceiling
        ));
        if let Some(rate) = b.ray_traced_images_per_second {
            derived.push_str(&format!(
                "| batch images / s with ray tracing (one run) | {rate:.2} |\n"
            ));
        }
    }
    if let Some(s) = &r.startup {
        row(
            "startup",
            format!(
                "cold (every cache empty, the driver's too): `{}`",
                s.command
            ),
            &s.cold,
        );
        row(
            "startup",
            "shikki's caches empty, the driver's shader cache filled".into(),
            &s.driver_cache_only,
        );
        row("startup", "warm (every cache filled)".into(), &s.warm);
    }
    if let Some(rays) = &r.rays {
        let what = format!(
            "default scene {}², {} samples (GPU)",
            rays.width, rays.samples
        );
        row("rays", format!("{what}, no ray tracing"), &rays.off_gpu);
        row(
            "rays",
            format!(
                "{what}, shadows + {} bounce(s) × {} rays",
                rays.bounces, rays.rays
            ),
            &rays.on_gpu,
        );
        row(
            "rays",
            "same, of which the denoise on the device (GPU)".into(),
            &rays.denoise_gpu,
        );
        for b in rays.bottom_level.iter().chain([&rays.top_level]) {
            row(
                "rays",
                format!(
                    "acceleration structure build: {} ({} primitives, {:.2} MiB)",
                    b.name,
                    b.primitives,
                    b.bytes as f64 / (1024.0 * 1024.0)
                ),
                &b.build,
            );
        }
        row(
            "rays",
            "512² sphere-on-board `shikki render`, whole process (wall)".into(),
            &rays.sphere_on_board_process,
        );
    }
    if let Some(m) = &r.memory {
        derived.push_str(&format!(
            "| memory: peak RSS cold / warm ({}²) | {:.0} / {:.0} MiB |\n",
            m.image_side, m.cold_peak_mib.median, m.warm_peak_mib.median
        ));
    }
    if !derived.is_empty() {
        out.push_str("\n| derived | value |\n|---|---|\n");
        out.push_str(&derived);
    }
    out.push_str("\n| target | value | limit | met |\n|---|---|---|---|\n");
    for t in &r.targets {
        out.push_str(&format!(
            "| {} | {:.3} | {} {} | {} |\n",
            t.description,
            t.value,
            if t.at_least { "≥" } else { "≤" },
            t.limit,
            if t.met { "yes" } else { "**no**" }
        ));
    }
    out
}
