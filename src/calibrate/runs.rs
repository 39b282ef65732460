//! The observed runs of a campaign, as calibration sees them: release state, block, observed rest point and the
//! release group each run belongs to.
//!
//! **Release groups** (ours): runs of the same block whose release points chain together within
//! `group_link_m` (single linkage). A group is what the field calls "repeated runs from one release point": at
//! Tschamut each block was released again and again from one small area (data.md), which gives one group per block.
//! The scatter floor and the group-wise objective compare a run only with its repeats, because runs of other blocks
//! or from elsewhere are not repeats of it. A calibration links its calibration runs alone
//! ([`calibration_groups`]), so that a held-out release point cannot chain two of their groups.

use super::model::RunSims;
use crate::campaign::Campaign;
use crate::error::{Error, Result};
use crate::terrain::UpAxis;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One observed run (`Default`: empty, with no track, for builders to fill in).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FieldRun {
    /// `trajectory_id`.
    pub id: String,
    /// Position in the campaign's release file: it keys the run's random streams, so a run gets the same
    /// streams whatever subset it is simulated in.
    pub index: usize,
    /// Block id.
    pub block_id: String,
    /// Block mass, kg.
    pub mass_kg: f64,
    /// Block bounding sizes sorted longest first, m.
    pub size_m: [f64; 3],
    /// Release position of the centre of mass, m, in the model's frame: the campaign's axes, but for a y-up terrain
    /// ([`crate::terrain::UpAxis::Y`]) talus's z-up ones (x, −z, y), so that x, y are horizontal and z is up for
    /// every model (so too the velocity, spin and rest position).
    pub release_m: [f64; 3],
    /// Initial velocity, m/s.
    pub velocity_mps: [f64; 3],
    /// Initial spin, rad/s.
    pub spin_radps: [f64; 3],
    /// Observed rest position, m.
    pub rest_m: [f64; 3],
    /// Observed run-out, m.
    pub runout_m: f64,
    /// Release group index.
    pub group: usize,
    /// Observed rebound height ([`super::rebound`]) from the run's tracked path, m; `None` without one.
    pub rebound_height_m: Option<f64>,
    /// Times of the run's tracked points since the first, s (empty without a track).
    pub track_times_s: Vec<f64>,
    /// How far the track's heights scatter around a smooth path, m ([`super::rebound::track_scatter_m`]); `None`
    /// without a track of at least 6 points.
    pub track_scatter_m: Option<f64>,
    /// The impacts read from the run's track ([`super::impacts`]); empty without a track.
    pub impacts: Vec<super::impacts::Impact>,
}

impl FieldRun {
    /// True if the run's track shows a bounce with a tangential restitution (the bounce score's,
    /// [`super::objective::bounce_crps`]).
    pub fn has_tangential_bounce(&self) -> bool {
        self.impacts.iter().any(|i| i.tangential_restitution.is_some())
    }

    /// True if the field rock left its release: it ran farther than [`NOT_STARTED_M`].
    pub fn ran(&self) -> bool {
        self.runout_m > NOT_STARTED_M
    }

    /// Elongation a/b of the sorted sizes (≥ 1).
    pub fn elongation(&self) -> f64 {
        self.size_m[0] / self.size_m[1]
    }

    /// Flatness b/c of the sorted sizes (≥ 1; a plate is flat).
    pub fn flatness(&self) -> f64 {
        self.size_m[1] / self.size_m[2]
    }

    /// Area of the block's largest face per unit mass, a·b/m of the sorted sizes, m²/kg.
    pub fn area_per_mass_m2_kg(&self) -> f64 {
        self.size_m[0] * self.size_m[1] / self.mass_kg
    }

    /// Nominal size: the geometric mean of the three sizes, m.
    pub fn size_nominal_m(&self) -> f64 {
        (self.size_m[0] * self.size_m[1] * self.size_m[2]).cbrt()
    }
}

/// The runs of a campaign that have an observed rest point, in file order, with their release groups; in the model's
/// frame for files whose up axis is `up` (z for profiles): [`FieldRun::release_m`].
pub fn field_runs(campaign: &Campaign, group_link_m: f64, up: UpAxis) -> Result<(Vec<FieldRun>, ReleaseGroups)> {
    let mut runs = Vec::new();
    for (index, r) in campaign.releases.iter().enumerate() {
        let Some(dep) = campaign.depositions.get(&r.trajectory_id) else { continue };
        let block = &campaign.blocks[&r.block_id];
        let mut size = block.size_m;
        size.sort_by(|a, b| b.total_cmp(a));
        let turn = |p: [f64; 3]| -> [f64; 3] { up.to_internal(p).into() };
        runs.push(FieldRun {
            id: r.trajectory_id.clone(),
            index,
            block_id: r.block_id.clone(),
            mass_kg: block.mass_kg,
            size_m: size,
            release_m: turn(r.position_m),
            velocity_mps: turn(r.velocity_mps),
            spin_radps: turn(r.spin_radps),
            rest_m: turn(dep.position_m),
            runout_m: dep.runout_m,
            ..Default::default()
        });
    }
    if runs.len() < 6 {
        let path = campaign.dir.join("observed_deposition.csv");
        let what = if path.exists() {
            format!("only {} runs have an observed rest point", runs.len())
        } else {
            "does not exist: a calibration needs the runs' observed rest points".to_string()
        };
        return Err(Error::format(
            path.display().to_string(),
            what,
            "calibration needs at least 6 observed runs (and more to hold some out), one row each: trajectory_id, \
             x_m, y_m, z_m (docs/campaign.md)",
        ));
    }
    let groups = assign_groups(&mut runs, group_link_m);
    Ok((runs, groups))
}

/// The release groups of a set of runs: their names (`block:k`, indexed by [`FieldRun::group`]) and the distance
/// that linked them.
#[derive(Debug, Clone, PartialEq)]
pub struct ReleaseGroups {
    /// Group names, `block:k` with k counting within the block in order of first appearance (a calibration's
    /// groups: among its calibration runs first, [`calibration_groups`]).
    pub names: Vec<String>,
    /// Release points of one block within this distance of each other are linked, m (`group_link_m`).
    pub link_m: f64,
}

/// Single-linkage release groups within each block; sets each run's group and returns the groups.
pub fn assign_groups(runs: &mut [FieldRun], link_m: f64) -> ReleaseGroups {
    let all: Vec<usize> = (0..runs.len()).collect();
    link_groups(runs, &all, link_m)
}

/// The runs with the release groups a calibration on runs `cal` sees (ours): the calibration runs linked among
/// themselves alone, so that no other run's release point (a held-out one) can chain two of their groups into
/// one and change what the fit and the loop choose. Every other run joins the group of the nearest calibration
/// run of its block within `link_m`, or else a group of its own, linked with the other such runs. With `cal` all
/// runs these are [`assign_groups`]'s groups.
pub fn calibration_groups(runs: &[FieldRun], cal: &[usize], link_m: f64) -> (Vec<FieldRun>, ReleaseGroups) {
    let mut runs = runs.to_vec();
    let groups = link_groups(&mut runs, cal, link_m);
    (runs, groups)
}

/// Links the runs of `cal` within each block (single linkage at `link_m`), attaches every other run to its nearest
/// linked run within `link_m`, and links the rest among themselves.
fn link_groups(runs: &mut [FieldRun], cal: &[usize], link_m: f64) -> ReleaseGroups {
    let n = runs.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], i: usize) -> usize {
        let mut r = i;
        while p[r] != r {
            r = p[r];
        }
        let mut k = i;
        while p[k] != r {
            let next = p[k];
            p[k] = r;
            k = next;
        }
        r
    }
    let distance =
        |a: &FieldRun, b: &FieldRun| (a.release_m[0] - b.release_m[0]).hypot(a.release_m[1] - b.release_m[1]);
    let linked = |a: &FieldRun, b: &FieldRun| a.block_id == b.block_id && distance(a, b) <= link_m;
    let mut in_cal = vec![false; n];
    for &i in cal {
        in_cal[i] = true;
    }
    let union = |p: &mut [usize], i: usize, j: usize| {
        let (a, b) = (find(p, i), find(p, j));
        if a != b {
            p[a.max(b)] = a.min(b);
        }
    };
    for i in 0..n {
        for j in i + 1..n {
            if in_cal[i] && in_cal[j] && linked(&runs[i], &runs[j]) {
                union(&mut parent, i, j);
            }
        }
    }
    // Each other run joins one calibration run at most, so no two calibration groups merge through it.
    let mut alone = Vec::new();
    for i in (0..n).filter(|&i| !in_cal[i]) {
        let nearest = (0..n)
            .filter(|&j| in_cal[j] && linked(&runs[i], &runs[j]))
            .min_by(|&a, &b| distance(&runs[i], &runs[a]).total_cmp(&distance(&runs[i], &runs[b])));
        match nearest {
            Some(j) => union(&mut parent, i, j),
            None => alone.push(i),
        }
    }
    for (k, &i) in alone.iter().enumerate() {
        for &j in &alone[k + 1..] {
            if linked(&runs[i], &runs[j]) {
                union(&mut parent, i, j);
            }
        }
    }
    // Numbered in order of first appearance among the calibration runs, then among the others, so that no other
    // run shifts the calibration groups' numbers either (inner folds are dealt in group order).
    let mut root_to_group: BTreeMap<usize, usize> = BTreeMap::new();
    let mut names = Vec::new();
    let mut per_block: BTreeMap<&str, usize> = BTreeMap::new();
    let mut group = vec![0; n];
    for i in (0..n).filter(|&i| in_cal[i]).chain((0..n).filter(|&i| !in_cal[i])) {
        let root = find(&mut parent, i);
        group[i] = *root_to_group.entry(root).or_insert_with(|| {
            let k = per_block.entry(&runs[i].block_id).or_insert(0);
            *k += 1;
            names.push(format!("{}:{}", runs[i].block_id, k));
            names.len() - 1
        });
    }
    for (run, g) in runs.iter_mut().zip(group) {
        run.group = g;
    }
    ReleaseGroups { names, link_m }
}

/// True if two runs are the same record: same block, and release position, initial velocity and rest point
/// equal to the micrometre. A duplicated record weighs twice in every fit, and on both sides of a split it would
/// be a held-out run the calibration saw, so splits and folds keep copies together ([`super::split::folds`]); it is
/// reported, not removed (ours: the data are the user's).
pub fn same_record(a: &FieldRun, b: &FieldRun) -> bool {
    let same = |p: &[f64; 3], q: &[f64; 3]| p.iter().zip(q).all(|(u, v)| (u - v).abs() < 1e-6);
    a.block_id == b.block_id
        && same(&a.release_m, &b.release_m)
        && same(&a.velocity_mps, &b.velocity_mps)
        && same(&a.rest_m, &b.rest_m)
}

/// A simulated rock that ends within this horizontal distance of its release has not started, m (ours).
pub const NOT_STARTED_M: f64 = 1.0;

/// A run's simulations stall in this share or more: its median is near a flip (ours: 2 of 20 repeats).
pub const STALLING_SHARE: f64 = 0.1;

/// The share of a run's simulations that end within [`NOT_STARTED_M`] of the release.
pub fn stalled_share(s: &RunSims) -> f64 {
    if s.sims.is_empty() {
        return 0.0;
    }
    s.sims.iter().filter(|x| x.stalled()).count() as f64 / s.sims.len() as f64
}

/// A run some of whose simulations stall at the release while the field rock ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StallingRun {
    /// The run.
    pub trajectory_id: String,
    /// `calibration` or `holdout`.
    pub set: String,
    /// Share of its simulations that end within [`NOT_STARTED_M`] of the release.
    pub stalled_share: f64,
}

/// The runs of `sims` (of the set `set`) whose field rock ran farther than [`NOT_STARTED_M`] and whose simulations
/// stall in [`STALLING_SHARE`] or more of the repeats. Such a run's outcome is two-valued in the model (the rock stops
/// where it was released or runs the slope), so its median, and the run-out MAE and coverage with it, flip when the
/// share crosses one half; a slow release on gentle ground under a high static friction does this (ours).
pub fn runs_stalling(runs: &[FieldRun], sims: &[RunSims], set: &str) -> Vec<StallingRun> {
    sims.iter()
        .filter(|s| runs[s.run].ran())
        .map(|s| (s, stalled_share(s)))
        .filter(|&(_, share)| share >= STALLING_SHARE)
        .map(|(s, share)| StallingRun { trajectory_id: runs[s.run].id.clone(), set: set.into(), stalled_share: share })
        .collect()
}

/// The runs of `sims` whose simulations all end within [`NOT_STARTED_M`] of the release while the field rock ran
/// farther: the model cannot start the rock from its recorded state (at rest on ground gentler than the friction
/// angle, for a block pushed off by hand, or terrain that is wrong at the release). Their error is the release's,
/// not the parameters'; they are reported, not removed (ours).
pub fn runs_not_started(runs: &[FieldRun], sims: &[RunSims]) -> Vec<String> {
    sims.iter().filter(|s| runs[s.run].ran() && stalled_share(s) == 1.0).map(|s| runs[s.run].id.clone()).collect()
}

/// Pairs of runs that are the same record ([`same_record`]), by `trajectory_id`.
pub fn duplicate_runs(runs: &[FieldRun]) -> Vec<[String; 2]> {
    let mut out = Vec::new();
    for (i, a) in runs.iter().enumerate() {
        for b in runs[i + 1..].iter().filter(|b| same_record(a, b)) {
            out.push([a.id.clone(), b.id.clone()]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn released_at(x: &[f64]) -> Vec<FieldRun> {
        x.iter()
            .enumerate()
            .map(|(i, &x)| FieldRun {
                id: format!("r{i}"),
                index: i,
                block_id: "b".into(),
                release_m: [x, 0.0, 0.0],
                ..Default::default()
            })
            .collect()
    }

    fn groups_of(runs: &[FieldRun]) -> Vec<usize> {
        runs.iter().map(|r| r.group).collect()
    }

    #[test]
    fn a_held_out_release_point_does_not_chain_two_calibration_groups() {
        // Releases at 0, 8 and 20 m with link 5 m; a held-out one at 4 m lies within 5 m of the first two.
        let mut all = released_at(&[0.0, 8.0, 4.0, 20.0, 24.0, 40.0]);
        let linked = assign_groups(&mut all, 5.0);
        assert_eq!(groups_of(&all), vec![0, 0, 0, 1, 1, 2], "all runs together chain 0, 4 and 8 m");
        assert_eq!(linked.names, vec!["b:1", "b:2", "b:3"]);
        // Held out: the run at 4 m (nearest calibration run: 0 m, at 4 against 4 m: the first), the run at 24 m
        // (joins 20 m) and the run at 40 m (alone).
        let cal = [0, 1, 3];
        let (runs, groups) = calibration_groups(&all, &cal, 5.0);
        assert_eq!(groups_of(&runs), vec![0, 1, 0, 2, 2, 3]);
        assert_eq!(groups.names, vec!["b:1", "b:2", "b:3", "b:4"]);
        assert_eq!(groups.link_m, 5.0);
        // Moving the held-out runs changes no calibration run's group.
        let mut moved = all.clone();
        moved[2].release_m[0] = 6.0;
        moved[4].release_m[0] = 30.0;
        let (runs_moved, _) = calibration_groups(&moved, &cal, 5.0);
        assert!(cal.iter().all(|&i| runs_moved[i].group == runs[i].group));
        assert_eq!(runs_moved[2].group, 1, "6 m is nearer 8 m than 0 m");
        // The calibration groups are numbered first: held-out runs earlier in the file shift no number.
        let (runs_late, _) = calibration_groups(&all, &[3, 4], 5.0);
        assert_eq!(groups_of(&runs_late), vec![1, 1, 1, 0, 0, 2]);
        // With every run calibrating, the groups are assign_groups's; another block never links.
        let every: Vec<usize> = (0..all.len()).collect();
        assert_eq!(groups_of(&calibration_groups(&all, &every, 5.0).0), groups_of(&all));
        all[1].block_id = "c".into();
        let g = assign_groups(&mut all, 5.0);
        assert_eq!(groups_of(&all), vec![0, 1, 0, 2, 2, 3]);
        assert_eq!(g.names, vec!["b:1", "c:1", "b:2", "b:3"]);
    }
}
