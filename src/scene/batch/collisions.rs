//! The plan-wide output check: before anything renders, the file name of every job of the jobs
//! file — all of them, whatever `--shard` says, since shards usually share one directory — is
//! computed, and a plan is refused if two jobs would write one file, a name is empty or too long,
//! or a name is the batch's own contact sheet.
//!
//! Names are compared after Unicode lower-casing: macOS and Windows disks are case-insensitive,
//! and a jobs file must not lose images on them that it keeps on Linux.
//!
//! Owns only the check and its error; names come from [`super::name`]. Never touches the disk.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

use super::name::{escape_value, extension, shortest_placeholder, Template, MAX_FILE_NAME_BYTES};
use super::{BatchPlan, JobSpec};
use crate::output::OutputFormat;
use crate::{Error, Result};

/// The check described in the module doc. Jobs whose format cannot be read write nothing (they
/// fail when prepared), so they are not compared.
pub(super) fn check_outputs(plan: &BatchPlan) -> Result<()> {
    let count = plan.job_count();
    let template = Template::parse(&plan.name_template, &plan.sweeps, count, &plan.name_at)?;
    let namer = Namer::new(plan, &template);
    // (hash of the folded name, id): 16 bytes a job, where a million names would be ~100 MB.
    let mut keys = Vec::with_capacity(count);
    let mut digits = vec![0; plan.sweeps.len()];
    for id in 0..count {
        let Some(name) = namer.name(id, &mut digits) else {
            continue;
        };
        check_one(plan, id, &name)?;
        keys.push((hash(&fold(&name)), id));
    }
    keys.sort_unstable();
    // Equal hashes are then compared by name: (first id of a name, another id of it).
    let mut clashes = Vec::new();
    for same_hash in keys.chunk_by(|a, b| a.0 == b.0).filter(|g| g.len() > 1) {
        let mut named: Vec<(String, usize)> = same_hash
            .iter()
            .filter_map(|&(_, id)| Some((fold(&namer.name(id, &mut digits)?), id)))
            .collect();
        named.sort();
        for same_name in named.chunk_by(|a, b| a.0 == b.0) {
            clashes.extend(same_name[1..].iter().map(|&(_, id)| (same_name[0].1, id)));
        }
    }
    match clashes.iter().min_by_key(|&&(first, other)| (other, first)) {
        None => Ok(()),
        Some(&(first, other)) => {
            let names = [first, other].map(|id| namer.name(id, &mut digits).unwrap_or_default());
            Err(clash_error(
                plan,
                &template,
                [first, other],
                names,
                clashes.len(),
            ))
        }
    }
}

/// Computes job names without building a [`JobSpec`] per job: each sweep value is escaped once.
struct Namer<'p> {
    plan: &'p BatchPlan,
    template: &'p Template<'p>,
    escaped: Vec<Vec<String>>,
    /// The format of every job, unless a sweep sets it.
    fixed_format: Option<Result<OutputFormat>>,
    /// The sweeps that may change `[output] format`, applied per job as `prepare` does.
    format_sweeps: Vec<usize>,
}

impl<'p> Namer<'p> {
    fn new(plan: &'p BatchPlan, template: &'p Template<'p>) -> Self {
        let escaped = plan
            .sweeps
            .iter()
            .map(|s| {
                s.values
                    .iter()
                    .map(|v| escape_value(&v.value.to_text()))
                    .collect()
            })
            .collect();
        let format_sweeps: Vec<usize> = (0..plan.sweeps.len())
            .filter(|&k| sets_format(&plan.sweeps[k].path))
            .collect();
        let fixed_format = format_sweeps.is_empty().then(|| plan.base.output_format());
        Namer {
            plan,
            template,
            escaped,
            fixed_format,
            format_sweeps,
        }
    }

    /// Job `id`'s file name, or `None` if its format is invalid (the job fails, writing nothing).
    fn name(&self, id: usize, digits: &mut [usize]) -> Option<String> {
        self.plan.digits(id, digits);
        let format = match &self.fixed_format {
            Some(format) => format.as_ref().ok().copied()?,
            None => self.swept_format(digits)?,
        };
        let values: Vec<&str> = self
            .escaped
            .iter()
            .zip(digits.iter())
            .map(|(values, &d)| values[d].as_str())
            .collect();
        Some(self.template.compose(id, &values, format))
    }

    fn swept_format(&self, digits: &[usize]) -> Option<OutputFormat> {
        let mut document = self.plan.base.clone();
        for &k in &self.format_sweeps {
            let sweep = &self.plan.sweeps[k];
            document
                .set_node(&sweep.path, sweep.values[digits[k]].clone())
                .ok()?;
        }
        document.output_format().ok()
    }
}

/// Whether setting `path` can change `[output] format`: `output`, `output.format` or below it.
fn sets_format(path: &str) -> bool {
    path == "output" || path == "output.format" || path.starts_with("output.format.")
}

/// A name that is empty, too long, or the batch's own file is refused on its own.
fn check_one(plan: &BatchPlan, id: usize, name: &str) -> Result<()> {
    let problem = if name.starts_with('.') {
        // Only an empty stem starts with `.`: a leading `.` of a value is escaped.
        Some("is empty, so it would be a hidden file with no name".to_string())
    } else if name.len() > MAX_FILE_NAME_BYTES {
        Some(format!(
            "is {} bytes long, more than the {MAX_FILE_NAME_BYTES} file systems allow",
            name.len()
        ))
    } else if is_contact_sheet(&fold(name)) {
        Some("is the batch's contact sheet".to_string())
    } else {
        None
    };
    match problem {
        None => Ok(()),
        Some(problem) => Err(plan.name_at.error(format!(
            "`name` = {:?}: {}'s file name {name:?} {problem}; change the template (a prefix \
             such as `job-`, fewer or shorter placeholders)",
            plan.name_template,
            describe(&plan.job(id)),
        ))),
    }
}

/// `contact_sheet.png` or `contact_sheet-shard-I-of-N.png`, already folded.
fn is_contact_sheet(folded: &str) -> bool {
    let Some(rest) = folded
        .strip_prefix("contact_sheet")
        .and_then(|r| r.strip_suffix(".png"))
    else {
        return false;
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    rest.is_empty()
        || rest
            .strip_prefix("-shard-")
            .and_then(|r| r.split_once("-of-"))
            .is_some_and(|(i, n)| digits(i) && digits(n))
}

fn fold(name: &str) -> String {
    name.to_lowercase()
}

/// Any hash would do: equal hashes are confirmed by comparing the names, and the clash reported
/// is the one with the smallest ids whatever the order.
fn hash(text: &str) -> u64 {
    let mut hasher = DefaultHasher::new();
    text.hash(&mut hasher);
    hasher.finish()
}

/// `job 2 (object.0.material.r = 1, camera.orbit_deg = 30)`.
fn describe(job: &JobSpec) -> String {
    let values: Vec<String> = job
        .values
        .iter()
        .map(|(path, v)| format!("{path} = {}", v.value.to_text()))
        .collect();
    match values.is_empty() {
        true => format!("job {}", job.id),
        false => format!("job {} ({})", job.id, values.join(", ")),
    }
}

/// Names both jobs, their values and the file, and the fix that fits why they met.
fn clash_error(
    plan: &BatchPlan,
    template: &Template,
    ids: [usize; 2],
    names: [String; 2],
    count: usize,
) -> Error {
    let [a, b] = ids.map(|id| plan.job(id));
    let text = |job: &JobSpec, k: usize| job.values[k].1.value.to_text();
    let differing: Vec<usize> = (0..plan.sweeps.len())
        .filter(|&k| text(&a, k) != text(&b, k))
        .collect();
    let file = if names[0] == names[1] {
        format!("would both write {}", names[0])
    } else {
        format!(
            "would write {} and {}, one file on a case-insensitive file system (macOS, Windows)",
            names[0], names[1]
        )
    };
    let fix = match differing.iter().find(|&&k| !template.uses(k)) {
        Some(&k) => {
            let placeholder = shortest_placeholder(k, &plan.sweeps);
            format!(
                "add {placeholder}, the sweep that tells them apart, to `name` (e.g. {:?}), or \
                 add {{job}}",
                with_placeholder(&plan.name_template, &placeholder)
            )
        }
        None if differing.is_empty() => "their swept values read the same: remove the repeated \
             value from its sweep, or add {job} to `name`"
            .to_string(),
        None if names[0] != names[1] => "their names differ only in letter case: add {job} to \
             `name`, or change the values"
            .to_string(),
        None => "the values run together in the name: put a separator such as `-` between the \
             placeholders, or add {job} to `name`"
            .to_string(),
    };
    let others = match count {
        1 => String::new(),
        n => format!(" ({n} jobs in all would overwrite another's image)"),
    };
    plan.name_at.error(format!(
        "`name` = {:?} gives two jobs one output file: {} and {} {file} in the output \
         directory{others}; {fix}",
        plan.name_template,
        describe(&a),
        describe(&b),
    ))
}

/// `template` with `-{placeholder}` added before its own `.png`/`.exr`, if it has one.
fn with_placeholder(template: &str, placeholder: &str) -> String {
    for format in [OutputFormat::Png, OutputFormat::Exr] {
        let ext = extension(format);
        if template.to_ascii_lowercase().ends_with(ext) {
            let (stem, suffix) = template.split_at(template.len() - ext.len());
            return format!("{stem}-{placeholder}{suffix}");
        }
    }
    format!("{template}-{placeholder}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn plan(name: &str, sweeps: &str) -> Result<BatchPlan> {
        let text = format!(
            "name = {name:?}\n[scene]\n[[scene.object]]\nmesh = \"builtin:sphere\"\n\
             [sweep]\n{sweeps}"
        );
        BatchPlan::parse(&text, "jobs.toml", Path::new("."))
    }

    const SWEEPS: &str = "\"object.0.material.preset\" = [\"smooth-red\", \"rough-red\"]\n\
        \"object.0.material.r\" = [1, 2, 3, 4, 5]\n\"camera.orbit_deg\" = [-30, 0, 30]\n";

    #[test]
    fn a_missing_sweep_is_named_with_both_jobs_and_the_fix() {
        let message = plan("{preset}-r{r}", SWEEPS).unwrap_err().to_string();
        for fragment in [
            "jobs.toml:1",
            "job 0 (object.0.material.preset = smooth-red, object.0.material.r = 1, \
             camera.orbit_deg = -30)",
            "job 1 (object.0.material.preset = smooth-red, object.0.material.r = 1, \
             camera.orbit_deg = 0)",
            "would both write smooth-red-r1.png",
            "20 jobs in all",
            "add {orbit_deg}, the sweep that tells them apart, to `name` \
             (e.g. \"{preset}-r{r}-{orbit_deg}\")",
        ] {
            assert!(message.contains(fragment), "{fragment:?} not in: {message}");
        }
    }

    #[test]
    fn the_signed_example_template_names_thirty_files() {
        assert!(plan("{preset}-r{r}-orbit{orbit_deg}", SWEEPS).is_ok());
    }

    #[test]
    fn names_equal_but_for_case_are_refused() {
        let message = plan("{preset}", "\"material.preset\" = [\"Red\", \"red\"]\n")
            .unwrap_err()
            .to_string();
        assert!(message.contains("Red.png and red.png"), "{message}");
        assert!(message.contains("only in letter case"), "{message}");
    }

    #[test]
    fn values_that_run_together_or_repeat_are_refused_with_their_own_fix() {
        let message = plan(
            "{r}{orbit_deg}",
            "\"object.0.material.r\" = [1, 11]\n\"camera.orbit_deg\" = [1, 11]\n",
        )
        .unwrap_err()
        .to_string();
        assert!(message.contains("would both write 111.png"), "{message}");
        assert!(message.contains("put a separator"), "{message}");
        let message = plan("r{r}", "\"object.0.material.r\" = [2, 3, 2.0]\n")
            .unwrap_err()
            .to_string();
        assert!(message.contains("job 0 (") && message.contains("job 2 ("));
        assert!(message.contains("remove the repeated value"), "{message}");
    }

    #[test]
    fn empty_long_and_reserved_names_are_refused() {
        let empty = plan("{preset}", "\"material.preset\" = [\"\", \"red\"]\n").unwrap_err();
        assert!(empty.to_string().contains("is empty"), "{empty}");
        let long = format!("{}{{job}}", "x".repeat(260));
        let long = plan(&long, "\"object.0.material.r\" = [1, 2]\n").unwrap_err();
        assert!(long.to_string().contains("bytes long"), "{long}");
        let sheet = plan(
            "contact_sheet{suffix}",
            "\"object.0.material.suffix\" = [\"\", \"-shard-0-of-2\"]\n",
        )
        .unwrap_err();
        assert!(sheet.to_string().contains("contact sheet"), "{sheet}");
        assert!(is_contact_sheet("contact_sheet-shard-1-of-4.png"));
        assert!(!is_contact_sheet("contact_sheet-red.png"));
    }

    #[test]
    fn a_swept_format_is_part_of_the_name() {
        // The same stem in two formats is two files.
        assert!(plan(
            "{r}",
            "\"object.0.material.r\" = [2]\n\"output.format\" = [\"png\", \"exr\"]\n"
        )
        .is_ok());
        let message = plan(
            "{r}.png",
            "\"object.0.material.r\" = [2]\n\"output.format\" = [\"png\", \"png\"]\n",
        )
        .unwrap_err()
        .to_string();
        assert!(message.contains("2.png"), "{message}");
    }
}
