//! Batch output names (issue 14), planned without a GPU: the example sweep names 30 distinct
//! files, shards of one jobs file never name one file, and a jobs file in which two jobs — even
//! of different shards — would share a file is refused when it is read, naming both jobs.

use std::collections::BTreeSet;
use std::path::Path;

use shikki::scene::batch::{in_shard, BatchPlan};

const EXAMPLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/examples/ratio-sweep.jobs.toml"
);

/// Every job's output file name as the run computes it (the job prepared: its scene built and its
/// format read).
fn names(plan: &BatchPlan, ids: impl Iterator<Item = usize>) -> Vec<String> {
    ids.map(|id| plan.prepare(&plan.job(id)).unwrap().file_name)
        .collect()
}

#[test]
fn the_example_sweep_names_thirty_distinct_files() {
    let plan = BatchPlan::load(Path::new(EXAMPLE)).unwrap();
    assert_eq!(plan.job_count(), 30);
    let all = names(&plan, 0..30);
    let distinct: BTreeSet<String> = all.iter().map(|n| n.to_lowercase()).collect();
    assert_eq!(distinct.len(), 30, "{all:?}");
    // -30° and 30° were both `orbit30` (the data loss of issue 14).
    assert_eq!(all[0], "smooth-red-r1-orbit-30.png");
    assert_eq!(all[1], "smooth-red-r1-orbit0.png");
    assert_eq!(all[2], "smooth-red-r1-orbit30.png");
}

#[test]
fn shards_of_one_jobs_file_never_name_one_file() {
    let plan = BatchPlan::load(Path::new(EXAMPLE)).unwrap();
    for n in 1..=7 {
        let mut seen = BTreeSet::new();
        for i in 0..n {
            for name in names(&plan, (0..30).filter(|&id| in_shard(id, (i, n)))) {
                assert!(
                    seen.insert(name.to_lowercase()),
                    "{name} twice with {n} shards"
                );
            }
        }
        assert_eq!(seen.len(), 30, "{n} shards");
    }
}

fn jobs(name: &str, sweeps: &str) -> shikki::Result<BatchPlan> {
    let text = format!(
        "name = {name:?}\n[scene]\n[[scene.object]]\nmesh = \"builtin:sphere\"\n[sweep]\n{sweeps}"
    );
    BatchPlan::parse(&text, "jobs.toml", Path::new("."))
}

#[test]
fn a_clash_between_two_shards_is_refused_although_neither_shard_clashes_alone() {
    // Shard 0/2 holds jobs 0 (a, r = 1) and 2 (b, r = 1): `a.png`, `b.png`; shard 1/2 holds 1
    // (a, r = 2) and 3: `a.png`, `b.png` again. Only the whole plan shows that they clash.
    let sweeps = "\"material.preset\" = [\"a\", \"b\"]\n\"object.0.material.r\" = [1, 2]\n";
    let message = jobs("{preset}", sweeps).unwrap_err().to_string();
    for fragment in [
        "jobs.toml:1",
        "job 0 (material.preset = a, object.0.material.r = 1)",
        "job 1 (material.preset = a, object.0.material.r = 2)",
        "would both write a.png",
        "add {r}, the sweep that tells them apart, to `name` (e.g. \"{preset}-{r}\")",
    ] {
        assert!(message.contains(fragment), "{fragment:?} not in: {message}");
    }
    assert!(jobs("{preset}-{r}", sweeps).is_ok());
}

#[test]
fn string_values_that_differ_only_in_punctuation_get_distinct_names() {
    let values = [
        "a b", "a-b", "a_b", "a:b", "a/b", "a\\b", "a%b", "ab", "a.b", "-ab", ".ab",
    ];
    let list: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
    let sweep = format!("\"object.0.material.tag\" = [{}]\n", list.join(", "));
    let plan = jobs("{tag}", &sweep).unwrap();
    let all: Vec<String> = plan
        .jobs()
        .iter()
        .map(|j| {
            plan.file_name(j, shikki::output::OutputFormat::Png)
                .unwrap()
        })
        .collect();
    assert_eq!(
        all.iter().collect::<BTreeSet<_>>().len(),
        values.len(),
        "{all:?}"
    );
    for name in &all {
        assert!(!name.contains(['/', '\\', ':', ' ']), "{name}");
        assert!(!name.starts_with(['.', '-']), "{name}");
    }
}
