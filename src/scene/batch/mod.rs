//! Batch rendering: a jobs file (a base scene plus sweeps) becomes one image per job.
//!
//! ```toml
//! scene = "bowl.toml"                    # the base scene (or an inline [scene] table)
//! name = "{preset}-r{r}-{orbit_deg}"     # output name template; .png/.exr added from the format
//! [sweep]                                # the cartesian product of these lists, first key outermost
//! "object.0.material.r" = [1, 2, 3]
//! "camera.orbit_deg" = [0, 45, 90]
//! ```
//!
//! Owns the plan (jobs, their ids and shards); [`name`] owns the file-name rule and `collisions`
//! the check, made when a plan is parsed and again before a run, that no two jobs of the whole
//! jobs file share an output file. [`run`] owns execution, [`manifest`] the CSV record and resume
//! rule, [`sheet`] the contact sheet, [`sink`] the atomic file writes. Rendering itself is
//! [`super::SceneRenderer`].

mod collisions;
pub mod encoders;
pub mod manifest;
pub mod name;
pub mod run;
pub mod sheet;
pub mod sink;

use std::path::Path;

use sha2::{Digest, Sha256};

use super::doc::{self, Node, Origin, Value};
use super::parse::{table_get, SceneDocument, MAX_SCENE_FILE_BYTES};
use super::Scene;
use crate::output::OutputFormat;
use crate::text::read_text_file;
use crate::Result;

pub use run::{run_batch, BatchObserver, BatchOptions, BatchSummary, Silent};
pub use sink::{FileSystem, OutputSink};

const JOBS_KEYS: &[&str] = &["scene", "name", "sweep"];
/// The most jobs one jobs file may describe (the product of its sweeps' lengths): a million
/// images is days of rendering, and a typo such as a 10⁴-value sweep × three more sweeps must
/// fail at once rather than overflow or allocate a job list of gigabytes.
pub const MAX_BATCH_JOBS: usize = 1_000_000;
/// Used when the jobs file has no `name`.
pub const DEFAULT_NAME_TEMPLATE: &str = "job-{job}";

/// One swept field: its path and the values it takes.
#[derive(Clone, Debug)]
pub struct Sweep {
    pub path: String,
    pub values: Vec<Node>,
}

/// A parsed jobs file.
#[derive(Clone, Debug)]
pub struct BatchPlan {
    pub base: SceneDocument,
    pub sweeps: Vec<Sweep>,
    pub name_template: String,
    name_at: Origin,
}

/// One job: its id (its index in the full cartesian product, independent of sharding) and the
/// value each sweep takes in it.
#[derive(Clone, Debug)]
pub struct JobSpec {
    pub id: usize,
    pub values: Vec<(String, Node)>,
}

/// A job ready to render.
#[derive(Clone, Debug)]
pub struct PreparedJob {
    pub scene: Scene,
    pub format: OutputFormat,
    /// The output file name (no directory).
    pub file_name: String,
    /// SHA-256 of the job's full scene (every resolved value), hex.
    pub scene_hash: String,
}

impl BatchPlan {
    /// Reads a jobs file (at most [`MAX_SCENE_FILE_BYTES`]); the base scene's relative paths
    /// resolve against the file naming them.
    pub fn load(path: &Path) -> Result<Self> {
        let text = read_text_file(path, MAX_SCENE_FILE_BYTES, "jobs")?;
        let base_dir = path.parent().unwrap_or(Path::new(""));
        Self::parse(&text, &path.display().to_string(), base_dir)
    }

    /// Parses jobs TOML (see the module doc).
    pub fn parse(text: &str, source: &str, base_dir: &Path) -> Result<Self> {
        let root = doc::parse_document(text, source, base_dir)?;
        let Value::Table(entries) = &root.value else {
            return Err(root.at.error("a jobs file is a TOML table"));
        };
        if let Some(bad) = entries
            .iter()
            .find(|e| !JOBS_KEYS.contains(&e.key.as_str()))
        {
            return Err(doc::unknown_key(bad, "the jobs file", JOBS_KEYS));
        }
        let scene = table_get(&root, "scene").ok_or_else(|| {
            root.at.error(
                "a jobs file needs `scene`: the path of a scene file, or an inline [scene] table",
            )
        })?;
        let base = match &scene.value {
            Value::Str(path) => SceneDocument::load(&doc::resolve_path(&scene.at, path))
                .map_err(|e| scene.at.error(e))?,
            Value::Table(_) => SceneDocument {
                root: scene.clone(),
            },
            _ => {
                return Err(scene.at.error(format!(
                    "`scene` must be a path or a table, found {}",
                    scene.value.type_name()
                )))
            }
        };
        let (name_template, name_at) = match table_get(&root, "name") {
            None => (DEFAULT_NAME_TEMPLATE.to_string(), root.at.clone()),
            Some(node) => match &node.value {
                Value::Str(s) if !s.trim().is_empty() => (s.clone(), node.at.clone()),
                _ => return Err(node.at.error("`name` must be a non-empty string template")),
            },
        };
        let mut sweeps = Vec::new();
        let mut sweep_at = root.at.clone();
        if let Some(sweep) = table_get(&root, "sweep") {
            sweep_at = sweep.at.clone();
            let Value::Table(entries) = &sweep.value else {
                return Err(sweep.at.error("[sweep] must be a table of path = [values]"));
            };
            for e in entries {
                match &e.node.value {
                    Value::Array(values) if !values.is_empty() => sweeps.push(Sweep {
                        path: e.key.clone(),
                        values: values.clone(),
                    }),
                    _ => {
                        return Err(e.node.at.error(format!(
                            "sweep `{}` must be a non-empty array of values, e.g. [1, 2, 3]",
                            e.key
                        )))
                    }
                }
            }
        }
        let count = sweeps
            .iter()
            .try_fold(1usize, |n, s| n.checked_mul(s.values.len()))
            .filter(|&n| n <= MAX_BATCH_JOBS);
        if count.is_none() {
            let lengths: Vec<String> = sweeps.iter().map(|s| s.values.len().to_string()).collect();
            return Err(sweep_at.error(format!(
                "the sweeps make {} jobs, more than the {MAX_BATCH_JOBS} one jobs file may hold; \
                 split the sweep into several jobs files",
                lengths.join(" × ")
            )));
        }
        let plan = BatchPlan {
            base,
            sweeps,
            name_template,
            name_at,
        };
        plan.check_template()?;
        plan.check_outputs()?;
        Ok(plan)
    }

    /// Number of jobs: the product of the sweeps' lengths (1 without sweeps).
    pub fn job_count(&self) -> usize {
        self.sweeps.iter().map(|s| s.values.len()).product()
    }

    /// Whether some job may trace rays: the base scene does, or a sweep sets a `render` key
    /// (conservative: `render.size` counts too). A base scene that does not build counts as
    /// tracing; its jobs fail on their own. Without rays the batch opens the device without its
    /// ray-tracing extensions (memory on NVIDIA's driver, `cli::open_gpu_tracing`).
    pub fn may_trace(&self) -> bool {
        self.sweeps.iter().any(|s| s.path.starts_with("render."))
            || self
                .base
                .build()
                .map_or(true, |scene| scene.render.ray_tracing_asked().is_some())
    }

    /// Every job, in id order; the first sweep varies slowest.
    pub fn jobs(&self) -> Vec<JobSpec> {
        (0..self.job_count()).map(|id| self.job(id)).collect()
    }

    /// Job `id` (mixed-radix digits of the id, last sweep fastest).
    pub fn job(&self, id: usize) -> JobSpec {
        let mut digits = vec![0; self.sweeps.len()];
        self.digits(id, &mut digits);
        JobSpec {
            id,
            values: self
                .sweeps
                .iter()
                .zip(digits)
                .map(|(sweep, d)| (sweep.path.clone(), sweep.values[d].clone()))
                .collect(),
        }
    }

    /// The index into each sweep's values of job `id`, into `digits` (one per sweep).
    fn digits(&self, id: usize, digits: &mut [usize]) {
        let mut rest = id;
        for (digit, sweep) in digits.iter_mut().zip(&self.sweeps).rev() {
            let n = sweep.values.len();
            *digit = rest % n;
            rest /= n;
        }
    }

    /// The scene, format, file name and hash of `job`.
    pub fn prepare(&self, job: &JobSpec) -> Result<PreparedJob> {
        let mut document = self.base.clone();
        for (path, value) in &job.values {
            document.set_node(path, value.clone())?;
        }
        let scene = document.build()?;
        let format = document.output_format()?;
        let file_name = self.file_name(job, format)?;
        let scene_hash = scene_hash(&scene, format);
        Ok(PreparedJob {
            scene,
            format,
            file_name,
            scene_hash,
        })
    }

    /// The template with `{job}` (the id, zero-padded to the width of the largest id) and
    /// `{path}` or `{last.segment}` of each sweep replaced, by the rule of [`name`].
    pub fn file_name(&self, job: &JobSpec, format: OutputFormat) -> Result<String> {
        let template = name::Template::parse(
            &self.name_template,
            &self.sweeps,
            self.job_count(),
            &self.name_at,
        )?;
        let escaped: Vec<String> = job
            .values
            .iter()
            .map(|(_, v)| name::escape_value(&v.value.to_text()))
            .collect();
        let values: Vec<&str> = escaped.iter().map(String::as_str).collect();
        Ok(template.compose(job.id, &values, format))
    }

    /// Refuses the plan if two of its jobs — of any shard — would write one file (names compared
    /// case-insensitively), or a name is empty, too long or the contact sheet's. Made by
    /// [`BatchPlan::parse`] and again by [`run_batch`] before anything is written.
    pub fn check_outputs(&self) -> Result<()> {
        collisions::check_outputs(self)
    }

    fn check_template(&self) -> Result<()> {
        let first = self.file_name(&self.job(0), OutputFormat::Png)?;
        if self.job_count() > 1 && !self.name_template.contains('{') {
            return Err(self.name_at.error(format!(
                "`name` = {:?} has no placeholder, so all {} jobs would write {}; add {{job}} or \
                 a swept field such as {{{}}}",
                self.name_template,
                self.job_count(),
                first,
                self.sweeps.first().map_or("job", |s| s.path.as_str())
            )));
        }
        Ok(())
    }
}

/// SHA-256 of every resolved value of the scene (Debug prints each f64 exactly) and the format.
/// Mesh and environment files enter by path, size and modification time.
pub fn scene_hash(scene: &Scene, format: OutputFormat) -> String {
    let mut hasher = Sha256::new();
    hasher.update(format!("{scene:?}|{format:?}").as_bytes());
    let mut stamp = |path: &Path| {
        if let Ok(m) = std::fs::metadata(path) {
            hasher.update(format!(
                "|{}:{}:{:?}",
                path.display(),
                m.len(),
                m.modified().ok()
            ));
        }
    };
    for object in &scene.objects {
        if let super::MeshSource::File(path) = &object.mesh {
            stamp(path);
        }
        if let Some(path) = &object.material.fresnel_file {
            stamp(path);
        }
    }
    if let super::EnvironmentSpec::Map {
        source: super::EnvironmentSource::Named(source),
        ..
    } = &scene.environment
    {
        stamp(Path::new(source));
    }
    hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// `I/N` with N ≥ 1 and I < N.
pub fn parse_shard(text: &str) -> std::result::Result<(usize, usize), String> {
    let err = || format!("shard {text:?}: expected I/N with 0 ≤ I < N, e.g. 0/4");
    let (i, n) = text.split_once('/').ok_or_else(err)?;
    let i: usize = i.trim().parse().map_err(|_| err())?;
    let n: usize = n.trim().parse().map_err(|_| err())?;
    if n == 0 || i >= n {
        return Err(err());
    }
    Ok((i, n))
}

/// Whether job `id` belongs to shard `i` of `n`: round-robin, so shards stay balanced whatever
/// the sweep order, and any two shards are disjoint and all together cover every id.
pub fn in_shard(id: usize, (i, n): (usize, usize)) -> bool {
    id % n == i
}

#[cfg(test)]
mod tests {
    use super::*;

    const JOBS: &str = "name = \"{preset}-r{r}-{job}\"\n\
        [scene]\n[[scene.object]]\nmesh = \"builtin:sphere\"\n\
        [sweep]\n\"object.0.material.preset\" = [\"smooth-red\", \"rough-red\"]\n\
        \"object.0.material.r\" = [1, 2, 3]\n";

    #[test]
    fn sweep_is_the_cartesian_product_first_key_slowest() {
        let plan = BatchPlan::parse(JOBS, "jobs.toml", Path::new(".")).unwrap();
        assert_eq!(plan.job_count(), 6);
        let names: Vec<String> = plan
            .jobs()
            .iter()
            .map(|j| plan.file_name(j, OutputFormat::Png).unwrap())
            .collect();
        assert_eq!(
            names,
            [
                "smooth-red-r1-0.png",
                "smooth-red-r2-1.png",
                "smooth-red-r3-2.png",
                "rough-red-r1-3.png",
                "rough-red-r2-4.png",
                "rough-red-r3-5.png"
            ]
        );
        let job = plan.prepare(&plan.job(4)).unwrap();
        assert_eq!(job.scene.objects[0].material.lacquer_ratio, 2.0);
        assert_eq!(job.scene.objects[0].material.beckmann_m, 0.20);
    }

    #[test]
    fn a_batch_may_trace_unless_its_base_does_not_and_no_sweep_sets_a_render_key() {
        let plan = |render: &str, sweep: &str| {
            let text = format!(
                "[scene]\n[scene.render]\n{render}\n[[scene.object]]\nmesh = \"builtin:sphere\"\n\
                 [sweep]\n\"object.0.material.r\" = [1, 2]\n{sweep}"
            );
            BatchPlan::parse(&text, "jobs.toml", Path::new(".")).unwrap()
        };
        assert!(plan("", "").may_trace(), "ray tracing is on by default");
        assert!(!plan("ray_tracing = false", "").may_trace());
        assert!(!plan("shadows = false\nbounces = 0", "").may_trace());
        assert!(plan(
            "ray_tracing = false",
            "\"render.ray_tracing\" = [false, true]"
        )
        .may_trace());
        assert!(plan(
            "shadows = false\nbounces = 0",
            "\"render.bounces\" = [0, 1]"
        )
        .may_trace());
    }

    #[test]
    fn shards_are_disjoint_and_cover_every_job() {
        for n in 1..6 {
            for id in 0..40 {
                let owners = (0..n).filter(|&i| in_shard(id, (i, n))).count();
                assert_eq!(owners, 1, "job {id} with {n} shards");
            }
        }
        assert_eq!(parse_shard("1/2"), Ok((1, 2)));
        assert!(parse_shard("2/2").is_err() && parse_shard("0/0").is_err());
    }

    #[test]
    fn hash_changes_with_any_swept_value_and_only_then() {
        let plan = BatchPlan::parse(JOBS, "jobs.toml", Path::new(".")).unwrap();
        let hashes: Vec<String> = plan
            .jobs()
            .iter()
            .map(|j| plan.prepare(j).unwrap().scene_hash)
            .collect();
        let again = plan.prepare(&plan.job(0)).unwrap().scene_hash;
        assert_eq!(hashes[0], again);
        let mut unique = hashes.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), 6);
    }

    #[test]
    fn too_many_jobs_are_rejected_before_any_is_listed() {
        let values: Vec<String> = (0..1000).map(|k| k.to_string()).collect();
        let list = format!("[{}]", values.join(", "));
        let text = format!(
            "[scene]\n[[scene.object]]\nmesh = \"builtin:sphere\"\n[sweep]\n\
             \"camera.orbit_deg\" = {list}\n\"object.0.material.r\" = {list}\n\
             \"camera.fov_deg\" = {list}\n"
        );
        let err = BatchPlan::parse(&text, "jobs.toml", Path::new(".")).unwrap_err();
        assert!(err.to_string().contains("1000 × 1000 × 1000 jobs"), "{err}");
    }

    #[test]
    fn template_without_placeholder_is_rejected_for_many_jobs() {
        let text = JOBS.replace("{preset}-r{r}-{job}", "same");
        let err = BatchPlan::parse(&text, "jobs.toml", Path::new(".")).unwrap_err();
        assert!(err.to_string().contains("jobs.toml:1"), "{err}");
    }
}
