//! Which runs calibrate and which are held out, and the folds of cross-validations.
//!
//! Splits and folds are stratified by release group (ours): each group is shuffled with a seeded stream and dealt
//! round-robin, so every group is represented on both sides in proportion and the held-out error speaks for every
//! block. Everything is a function of the seed alone.

use super::runs::{same_record, FieldRun};
use super::stats::shuffle;
use crate::error::{Error, Result};
use crate::random::stream;
use std::collections::BTreeMap;
use std::path::Path;

/// Stream index base for splits and folds (apart from simulation streams, which use run << 24).
const SPLIT_STREAM: u64 = u64::MAX - 1000;

/// Reads a hold-out file: one `trajectory_id` per line (blank lines and `#` comments ignored). Returns the indices
/// of those runs, and of the copies of any duplicated record among them ([`same_record`]), which are held out with
/// it. Every id must be a run with an observed rest point.
pub fn read_holdout(path: &Path, runs: &[FieldRun]) -> Result<Vec<usize>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    // A leading byte-order mark (editors on Windows write one) is not part of the first id.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let id = line.split('#').next().unwrap_or("").trim();
        if id.is_empty() {
            continue;
        }
        let Some(i) = runs.iter().position(|r| r.id == id) else {
            return Err(Error::at_line(
                path,
                k + 1,
                format!("'{id}' is not an observed run of the campaign"),
                "list trajectory_ids from observed_deposition.csv, one per line",
            ));
        };
        if !out.contains(&i) {
            out.push(i);
        }
    }
    if out.is_empty() {
        return Err(Error::format(path.display().to_string(), "lists no run", "put one trajectory_id per line"));
    }
    for (i, r) in runs.iter().enumerate() {
        if !out.contains(&i) && out.iter().any(|&j| same_record(r, &runs[j])) {
            out.push(i);
        }
    }
    if out.len() + 3 > runs.len() {
        return Err(Error::format(
            path.display().to_string(),
            format!("holds out {} of {} runs", out.len(), runs.len()),
            "keep at least 3 runs to calibrate on",
        ));
    }
    out.sort();
    Ok(out)
}

/// Assigns every run to one of `k` folds, stratified by release group; returns the fold of each run. A copy of a
/// duplicated record ([`same_record`]) goes to the fold of its first copy.
pub fn folds(runs: &[FieldRun], which: &[usize], k: usize, seed: u64, purpose: u64) -> Vec<usize> {
    let mut by_group: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (pos, &i) in which.iter().enumerate() {
        by_group.entry(runs[i].group).or_default().push(pos);
    }
    let mut rng = stream(seed, SPLIT_STREAM - purpose);
    let mut fold = vec![0usize; which.len()];
    let mut next = 0usize;
    for members in by_group.values_mut() {
        shuffle(members, &mut rng);
        for &pos in members.iter() {
            fold[pos] = next % k;
            next += 1;
        }
    }
    for j in 0..which.len() {
        if let Some(i) = (0..j).find(|&i| same_record(&runs[which[i]], &runs[which[j]])) {
            fold[j] = fold[i];
        }
    }
    fold
}

/// A seeded split: about `fraction` of each release group held out. Returns (calibration, hold-out) run indices.
pub fn seeded_split(runs: &[FieldRun], fraction: f64, seed: u64) -> (Vec<usize>, Vec<usize>) {
    let k = (1.0 / fraction).round().max(2.0) as usize;
    let all: Vec<usize> = (0..runs.len()).collect();
    let f = folds(runs, &all, k, seed, 0);
    let hold: Vec<usize> = all.iter().copied().filter(|&i| f[i] == 0).collect();
    let cal: Vec<usize> = all.iter().copied().filter(|&i| f[i] != 0).collect();
    (cal, hold)
}
