//! Sizing each candidate from one run in which all candidates are collectors.
//!
//! **Protected zone.** With an asset line or polygon, a rock reaches the protected zone when it crosses the line
//! or enters the polygon; a candidate can intercept it only if the rock crosses the candidate first. Without one,
//! the protected zone of a candidate is the ground beyond it: a rock reaches it when it crosses the candidate line
//! (ours; the "beyond the candidate"). Call R the number of rocks that reach the protected zone.
//!
//! **Length.** Each rock that reaches the zone is counted in the stretch where it first crosses the candidate (if it
//! does, before reaching the zone). The proposed barrier is the shortest run of whole consecutive stretches (wrapping
//! round on closed lines) holding at least `target_share` × R of them (two pointers over the stretches). A barrier
//! there meets at least those rocks; it may meet more (rocks that first cross the line elsewhere and then cross the
//! barrier), so the share is a lower bound. If the whole line holds fewer, the barrier covers every stretch with such
//! rocks and the share reached is reported.
//!
//! **Design values** over the rocks crossing the barrier's stretches (each rock's first crossing of each stretch):
//! design height = P95 of the passing height of the lowest point + P95 of the rock size (the diameter of the sphere
//! of the rock's volume), so that a P95 rock passes the fence below its top with a whole rock to spare (ours, after
//! the issue: "P95 passing height plus the rock's size"); the fence height is that rounded up to 0.5 m (ours).
//! Design energy: P95 (default), P99 or maximum of the total kinetic energy, which picks the smallest energy class
//! that takes it ([`super::classes`]). Cost = length × cost per metre of the class.
//!
//! **Ranking** (ours). A proposal should, in this order of importance, meet the target share; be buildable (a
//! standard class, and a fence no higher than `max_fence_height_m`); and intercept at least `min_share_of_released`
//! of all released rocks. Sized candidates are ranked by whether they meet the target, then by how many of the two
//! buildability criteria they miss, then by whether they meet the share, then by cost (then fence height, then
//! length); each missed criterion is written in the `note` column. Candidates with fewer than `min_rocks` rocks
//! reaching their zone are listed but not sized (too few to estimate a P95).
//!
//! **Several models** (ours; `talus barrier --models`, made for the fold models of `talus calibrate --kfold`). Each
//! model runs the same rocks; the barrier is the shortest run of stretches that holds the target share in every
//! model, and its height and class are those of the model that asks most. The design then covers the calibration's
//! uncertainty as far as the models span it, not the single best fit's figures alone. With `across_models =
//! "pooled"` the models' rocks are one ensemble instead (see [`super::AcrossModels`]).

use super::candidates::{Candidate, CandidateKind};
use super::classes::{class_for, class_label, cost};
use super::settings::{AcrossModels, ClassEnergy, DesignSpec};
use crate::collector::{Collector, CollectorStats, Quantity, QuantityDists, RockCrossings};
use serde::Serialize;

/// Per-stretch counts of the rocks that reach each candidate's protected zone, gathered rock by rock.
#[derive(Debug, Clone, PartialEq)]
pub struct Tally {
    /// Index of the first candidate among the run's collectors.
    pub offset: usize,
    /// Whether an asset zone is tracked (else each candidate's zone is beyond it).
    pub asset_zone: bool,
    /// Rocks seen.
    pub rocks: u64,
    /// Rocks that reached the asset zone.
    pub zone_reached: u64,
    /// Per candidate, per stretch: rocks reaching the zone whose first crossing of the candidate is there.
    pub targeted: Vec<Vec<u32>>,
    /// Per candidate: rocks crossing it.
    pub crossing: Vec<u64>,
}

impl Tally {
    /// An empty tally for `candidates` (collectors `offset..` of the run).
    pub fn new(candidates: &[Collector], offset: usize, asset_zone: bool) -> Self {
        Tally {
            offset,
            asset_zone,
            rocks: 0,
            zone_reached: 0,
            targeted: candidates.iter().map(|c| vec![0; c.stretch_count()]).collect(),
            crossing: vec![0; candidates.len()],
        }
    }

    /// Adds a rock; `candidates` are the candidate collectors (the run's collectors from `offset` on).
    pub fn add(&mut self, r: &RockCrossings, candidates: &[Collector]) {
        self.rocks += 1;
        if r.zone_t_s.is_some() {
            self.zone_reached += 1;
        }
        for (c, x) in &r.line_first {
            let Some(k) = (*c as usize).checked_sub(self.offset) else { continue };
            if k >= self.targeted.len() {
                continue;
            }
            self.crossing[k] += 1;
            let reaches = if self.asset_zone { r.zone_t_s.is_some_and(|t| x.t_s <= t) } else { true };
            if reaches {
                let s = candidates[k].stretch_of(x.along_m);
                self.targeted[k][s] += 1;
            }
        }
    }

    /// Rocks that reach the protected zone of candidate `k`.
    pub fn reaching(&self, k: usize) -> u64 {
        if self.asset_zone {
            self.zone_reached
        } else {
            self.crossing[k]
        }
    }
}

/// What became of a candidate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Sized; see the values.
    Sized,
    /// Fewer than `min_rocks` rocks reach its protected zone.
    TooFewRocks,
}

/// A sized (or not) candidate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Assessment {
    /// Index into the candidate list.
    pub candidate: usize,
    /// Name.
    pub name: String,
    /// Where it comes from.
    pub kind: CandidateKind,
    /// Rank among the proposals (1 = best), if ranked.
    pub rank: Option<usize>,
    /// Sized or not.
    pub status: Status,
    /// Length of the whole candidate line, m.
    pub candidate_length_m: f64,
    /// Rocks reaching the protected zone (R).
    pub rocks_reaching: u64,
    /// Start and end of the proposed barrier along the candidate, m.
    pub from_m: f64,
    /// End along the candidate, m.
    pub to_m: f64,
    /// Barrier length, m.
    pub length_m: f64,
    /// Rocks of R intercepted (lower bound).
    pub intercepted: u64,
    /// Intercepted / R.
    pub share: f64,
    /// Intercepted / all rocks released.
    pub share_of_released: f64,
    /// Meets the target share.
    pub meets_target: bool,
    /// Rocks crossing the barrier's stretches.
    pub rocks_crossing: u64,
    /// P95 passing height, m.
    pub passing_height_p95_m: f64,
    /// Largest passing height, m.
    pub passing_height_max_m: f64,
    /// P95 rock size, m.
    pub rock_size_p95_m: f64,
    /// Design height (P95 passing height + P95 rock size), m.
    pub design_height_m: f64,
    /// Fence height: the design height rounded up to 0.5 m.
    pub fence_height_m: f64,
    /// P95 of the total kinetic energy, kJ.
    pub energy_p95_kj: f64,
    /// P99, kJ.
    pub energy_p99_kj: f64,
    /// Largest, kJ.
    pub energy_max_kj: f64,
    /// P95 speed, m/s.
    pub speed_p95_mps: f64,
    /// Median crossing angle, degrees.
    pub crossing_angle_p50_deg: f64,
    /// Energy class index (`None`: above the largest).
    #[serde(skip)]
    pub class: Option<usize>,
    /// Energy class, kJ (`None`: above the largest class).
    pub class_kj: Option<f64>,
    /// Energy class as written.
    pub class_label: String,
    /// Cost (length × class cost per metre); `None` above the largest class.
    pub cost: Option<f64>,
    /// Why it is not ranked first, or other remarks.
    pub note: String,
    /// The proposed barrier line (local frame).
    #[serde(skip)]
    pub line_m: Vec<[f64; 2]>,
    /// The model whose design height governs (see [`assess`]).
    pub height_from: String,
    /// The model whose design energy governs.
    pub energy_from: String,
    /// Each model's figures on the proposal's stretches (empty if not sized).
    #[serde(skip)]
    pub per_model: Vec<ModelDesign>,
}

/// One model's figures on a proposal's stretches (see [`assess`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelDesign {
    /// The model's name.
    pub model: String,
    /// Rocks reaching the protected zone in this model (R).
    pub rocks_reaching: u64,
    /// Rocks of R intercepted (lower bound).
    pub intercepted: u64,
    /// Intercepted / R.
    pub share: f64,
    /// Intercepted / all rocks released.
    pub share_of_released: f64,
    /// Enough rocks (`min_rocks`) reach the zone for this model to size the barrier.
    pub sizes: bool,
    /// Rocks crossing the barrier's stretches.
    pub rocks_crossing: u64,
    /// P95 passing height, m.
    pub passing_height_p95_m: f64,
    /// Largest passing height, m.
    pub passing_height_max_m: f64,
    /// P95 rock size, m.
    pub rock_size_p95_m: f64,
    /// P95 passing height + P95 rock size, m.
    pub design_height_m: f64,
    /// P95 of the total kinetic energy, kJ.
    pub energy_p95_kj: f64,
    /// P99, kJ.
    pub energy_p99_kj: f64,
    /// Largest, kJ.
    pub energy_max_kj: f64,
    /// The energy the class is chosen by (`class_energy`), kJ.
    pub design_energy_kj: f64,
    /// P95 speed, m/s.
    pub speed_p95_mps: f64,
    /// Median crossing angle, degrees.
    pub crossing_angle_p50_deg: f64,
}

/// One model's run without a barrier, every candidate a collector: what [`assess`] sizes from.
#[derive(Debug, Clone, Copy)]
pub struct ModelRun<'a> {
    /// The model's name.
    pub name: &'a str,
    /// The run's collectors (the scenario's, then the candidates).
    pub collectors: &'a [Collector],
    /// Their statistics.
    pub stats: &'a CollectorStats,
    /// The rocks reaching each candidate's zone, by stretch.
    pub tally: &'a Tally,
}

/// The shortest run of consecutive stretches (start, count) that holds, for every model `m`, at least `need[m]` of
/// `counts[m]` (circular if `closed`), by length; `None` if no run does or nothing is needed.
pub fn shortest_run(counts: &[&[u32]], lengths: &[f64], need: &[u64], closed: bool) -> Option<(usize, usize)> {
    let n = lengths.len();
    if n == 0 || need.iter().all(|&k| k == 0) {
        return None;
    }
    let limit = if closed { 2 * n } else { n };
    let at = |k: usize| k % n;
    let met = |sum: &[u64]| sum.iter().zip(need).all(|(s, k)| s >= k);
    let mut best: Option<(f64, usize, usize)> = None;
    let (mut end, mut sum, mut len) = (0usize, vec![0u64; need.len()], 0.0f64);
    for start in 0..n {
        if end < start {
            end = start;
            sum.iter_mut().for_each(|s| *s = 0);
            len = 0.0;
        }
        while !met(&sum) && end < limit && end - start < n {
            for (s, c) in sum.iter_mut().zip(counts) {
                *s += c[at(end)] as u64;
            }
            len += lengths[at(end)];
            end += 1;
        }
        if met(&sum) && best.is_none_or(|(l, _, _)| len < l - 1e-9) {
            best = Some((len, start, end - start));
        }
        for (s, c) in sum.iter_mut().zip(counts) {
            *s -= c[at(start)] as u64;
        }
        len -= lengths[at(start)];
    }
    best.map(|(_, s, c)| (s, c))
}

/// Sizes every candidate from one or more models' runs and ranks them.
///
/// With several models (the fold models of a calibration: the design against the calibration's uncertainty; ours)
/// the barrier is the shortest run of stretches that intercepts the target share in every model that sizes (at
/// least `min_rocks` reach its zone); the shares and counts are the worst such model's (lowest share), "meets
/// target" holds if it holds in each; the design height is the largest over them of P95 passing height + P95 rock
/// size (its two terms from that model), each energy and the speed the largest, the crossing angle that of the
/// model with the largest design energy. With one model these are its own figures. `per_model` keeps each model's.
pub fn assess(candidates: &[Candidate], runs: &[ModelRun], spec: &DesignSpec) -> Vec<Assessment> {
    let mut out: Vec<Assessment> = candidates
        .iter()
        .enumerate()
        .map(|(k, cand)| {
            let ci = runs[0].tally.offset + k;
            let col = &runs[0].collectors[ci];
            let reaching: Vec<u64> = runs.iter().map(|r| r.tally.reaching(k)).collect();
            let totals: Vec<u64> = runs.iter().map(|r| r.tally.targeted[k].iter().map(|&c| c as u64).sum()).collect();
            let min_rocks = spec.min_rocks.max(1) as u64;
            let sizes: Vec<bool> = reaching.iter().zip(&totals).map(|(&r, &t)| r >= min_rocks && t > 0).collect();
            let mut a = Assessment {
                candidate: k,
                name: cand.name.clone(),
                kind: cand.kind,
                rank: None,
                status: Status::TooFewRocks,
                candidate_length_m: col.length_m(),
                rocks_reaching: reaching.iter().copied().max().unwrap_or(0),
                from_m: 0.0,
                to_m: 0.0,
                length_m: 0.0,
                intercepted: 0,
                share: 0.0,
                share_of_released: 0.0,
                meets_target: false,
                rocks_crossing: 0,
                passing_height_p95_m: f64::NAN,
                passing_height_max_m: f64::NAN,
                rock_size_p95_m: f64::NAN,
                design_height_m: f64::NAN,
                fence_height_m: f64::NAN,
                energy_p95_kj: f64::NAN,
                energy_p99_kj: f64::NAN,
                energy_max_kj: f64::NAN,
                speed_p95_mps: f64::NAN,
                crossing_angle_p50_deg: f64::NAN,
                class: None,
                class_kj: None,
                class_label: String::new(),
                cost: None,
                note: String::new(),
                line_m: Vec::new(),
                height_from: String::new(),
                energy_from: String::new(),
                per_model: Vec::new(),
            };
            let pooled = spec.across_models == AcrossModels::Pooled && runs.len() > 1;
            let (reaching_all, total_all) = (reaching.iter().sum::<u64>(), totals.iter().sum::<u64>());
            let sized = if pooled { reaching_all >= min_rocks && total_all > 0 } else { sizes.iter().any(|&s| s) };
            if !sized {
                a.note = format!("{} rocks reach its protected zone (fewer than {min_rocks})", a.rocks_reaching);
                return a;
            }
            let need = |r: u64| ((spec.target_share * r as f64 - 1e-9).ceil() as u64).max(1);
            let lengths: Vec<f64> =
                (0..col.stretch_count()).map(|s| col.stretch_span_m(s)).map(|(a, b)| b - a).collect();
            // Pooled: one ensemble of every model's rocks; worst: every model's own counts and need.
            let summed: Vec<u32>;
            let (counts, needs): (Vec<&[u32]>, Vec<u64>) = if pooled {
                summed = (0..col.stretch_count()).map(|s| runs.iter().map(|r| r.tally.targeted[k][s]).sum()).collect();
                (vec![summed.as_slice()], vec![need(reaching_all).min(total_all)])
            } else {
                let needs = (0..runs.len()).map(|m| if sizes[m] { need(reaching[m]).min(totals[m]) } else { 0 });
                (runs.iter().map(|r| r.tally.targeted[k].as_slice()).collect(), needs.collect())
            };
            let (start, count) =
                shortest_run(&counts, &lengths, &needs, col.is_closed()).unwrap_or((0, col.stretch_count()));
            let stretches: Vec<usize> = (start..start + count).map(|s| s % col.stretch_count()).collect();
            let wraps = start + count > col.stretch_count();
            let (from, to) =
                (col.stretch_span_m(start).0, col.stretch_span_m((start + count - 1) % col.stretch_count()).1);
            a.line_m = if wraps {
                let mut l = col.sub_line(from, col.length_m());
                l.extend(col.sub_line(0.0, to).into_iter().skip(1));
                l
            } else {
                col.sub_line(from, to)
            };
            a.from_m = from;
            a.to_m = to;
            a.length_m = lengths.iter().enumerate().filter(|(s, _)| stretches.contains(s)).map(|(_, l)| l).sum();
            a.status = Status::Sized;
            let dists: Vec<QuantityDists> =
                runs.iter().map(|r| r.stats.stretch_range_dists(ci, stretches.iter().copied())).collect();
            let intercepted: Vec<u64> =
                runs.iter().map(|r| stretches.iter().map(|&s| r.tally.targeted[k][s] as u64).sum()).collect();
            let per_model: Vec<ModelDesign> = (runs.iter().enumerate())
                .map(|(m, run)| {
                    let counts = (reaching[m], intercepted[m], run.tally.rocks);
                    design_of(run.name, &dists[m], counts, sizes[m], spec)
                })
                .collect();
            // The figures the assessment takes: from the pooled rocks, or from the models that ask most.
            let (pooled_design, largest_of_each);
            let (counts, tall, strong, largest) = if pooled {
                let mut d = QuantityDists::default();
                dists.iter().for_each(|x| d.merge(x));
                let released = runs.iter().map(|r| r.tally.rocks).sum();
                let counts = (reaching_all, intercepted.iter().sum(), released);
                pooled_design = design_of("pooled", &d, counts, true, spec);
                a.meets_target = pooled_design.intercepted >= need(reaching_all);
                (&pooled_design, &pooled_design, &pooled_design, &pooled_design)
            } else {
                let sizing: Vec<(usize, &ModelDesign)> =
                    per_model.iter().enumerate().filter(|(m, _)| sizes[*m]).collect();
                let largest = |f: fn(&ModelDesign) -> f64| {
                    sizing.iter().map(|(_, d)| *d).max_by(|x, y| f(x).total_cmp(&f(y))).expect("a model sizes")
                };
                let strong = largest(|d| d.design_energy_kj);
                let fold = |f: fn(&ModelDesign) -> f64| sizing.iter().map(|(_, d)| f(d)).fold(f64::NAN, f64::max);
                largest_of_each = ModelDesign {
                    passing_height_max_m: fold(|d| d.passing_height_max_m),
                    energy_p95_kj: fold(|d| d.energy_p95_kj),
                    energy_p99_kj: fold(|d| d.energy_p99_kj),
                    energy_max_kj: fold(|d| d.energy_max_kj),
                    speed_p95_mps: fold(|d| d.speed_p95_mps),
                    ..strong.clone()
                };
                a.meets_target = sizing.iter().all(|(m, d)| d.intercepted >= need(reaching[*m]));
                (largest(|d| -d.share), largest(|d| d.design_height_m), strong, &largest_of_each)
            };
            take(&mut a, counts, tall, strong, largest);
            finish(&mut a, strong.design_energy_kj, spec);
            a.per_model = per_model;
            a
        })
        .collect();
    rank(&mut out, spec);
    out
}

/// One model's (or the pooled rocks') figures from the rocks crossing the proposal's stretches `d`; `counts` are
/// the rocks reaching the zone, those intercepted and all released.
fn design_of(model: &str, d: &QuantityDists, counts: (u64, u64, u64), sizes: bool, spec: &DesignSpec) -> ModelDesign {
    let (reaching, intercepted, released) = counts;
    let h95 = d.quantile(Quantity::Height, 0.95);
    let size95 = d.quantile(Quantity::Size, 0.95);
    let e = [0.95, 0.99].map(|q| d.quantile(Quantity::Kinetic, q));
    let e_max = d.max(Quantity::Kinetic);
    ModelDesign {
        model: model.to_string(),
        rocks_reaching: reaching,
        intercepted,
        share: intercepted as f64 / reaching.max(1) as f64,
        share_of_released: intercepted as f64 / released.max(1) as f64,
        sizes,
        rocks_crossing: d.count() as u64,
        passing_height_p95_m: h95,
        passing_height_max_m: d.max(Quantity::Height),
        rock_size_p95_m: size95,
        design_height_m: h95 + size95,
        energy_p95_kj: e[0],
        energy_p99_kj: e[1],
        energy_max_kj: e_max,
        design_energy_kj: match spec.class_energy {
            ClassEnergy::P95 => e[0],
            ClassEnergy::P99 => e[1],
            ClassEnergy::Max => e_max,
        },
        speed_p95_mps: d.quantile(Quantity::Speed, 0.95),
        crossing_angle_p50_deg: d.quantile(Quantity::Angle, 0.5),
    }
}

/// Fills an assessment's figures: counts and shares from `counts`, the height from `tall`, the class's model
/// from `strong`, the largest passing height, energies and speed from `largest`.
fn take(a: &mut Assessment, counts: &ModelDesign, tall: &ModelDesign, strong: &ModelDesign, largest: &ModelDesign) {
    a.rocks_reaching = counts.rocks_reaching;
    a.intercepted = counts.intercepted;
    a.share = counts.share;
    a.rocks_crossing = counts.rocks_crossing;
    a.share_of_released = counts.share_of_released;
    a.passing_height_p95_m = tall.passing_height_p95_m;
    a.rock_size_p95_m = tall.rock_size_p95_m;
    a.design_height_m = tall.design_height_m;
    a.height_from = tall.model.clone();
    a.passing_height_max_m = largest.passing_height_max_m;
    a.energy_p95_kj = largest.energy_p95_kj;
    a.energy_p99_kj = largest.energy_p99_kj;
    a.energy_max_kj = largest.energy_max_kj;
    a.speed_p95_mps = largest.speed_p95_mps;
    a.crossing_angle_p50_deg = strong.crossing_angle_p50_deg;
    a.energy_from = strong.model.clone();
}

/// The fence height, class (by `design_energy_kj`), cost and notes of a sized assessment.
fn finish(a: &mut Assessment, design_energy_kj: f64, spec: &DesignSpec) {
    a.fence_height_m = (a.design_height_m / 0.5).ceil() * 0.5;
    a.class = class_for(design_energy_kj, &spec.classes_kj);
    a.class_kj = a.class.map(|c| spec.classes_kj[c]);
    a.class_label = class_label(a.class, spec);
    a.cost = cost(a.length_m, a.class, spec);
    let mut notes = Vec::new();
    if !a.meets_target {
        notes.push(format!("intercepts {:.1} % < target {:.1} %", 100.0 * a.share, 100.0 * spec.target_share));
    }
    if a.share_of_released < spec.min_share_of_released {
        notes.push(format!(
            "stops {:.1} % of all rocks (< {:.0} %)",
            100.0 * a.share_of_released,
            100.0 * spec.min_share_of_released
        ));
    }
    if a.class.is_none() {
        notes.push("energy above the largest class: consider a dam or another position".into());
    }
    if a.fence_height_m > spec.max_fence_height_m {
        notes.push(format!("higher than a fence ({} m)", spec.max_fence_height_m));
    }
    a.note = notes.join("; ");
}

/// Ranks the sized assessments (see the module docs).
fn rank(out: &mut [Assessment], spec: &DesignSpec) {
    // Criteria a proposal should meet, most important first: the target share; a standard class and a fence height
    // that can be built; a useful share of all rocks. Candidates are ranked by what they miss, then by cost.
    let missed = |a: &Assessment| {
        let unbuildable = a.class.is_none() as u8 + (a.fence_height_m > spec.max_fence_height_m) as u8;
        (!a.meets_target, unbuildable, a.share_of_released < spec.min_share_of_released)
    };
    let mut order: Vec<usize> = (0..out.len()).filter(|&i| out[i].status == Status::Sized).collect();
    order.sort_by(|&i, &j| {
        let (a, b) = (&out[i], &out[j]);
        missed(a)
            .cmp(&missed(b))
            .then_with(|| match (a.cost, b.cost) {
                (Some(x), Some(y)) => x.total_cmp(&y),
                (Some(_), None) => std::cmp::Ordering::Less,
                (None, Some(_)) => std::cmp::Ordering::Greater,
                (None, None) => b.share.total_cmp(&a.share),
            })
            .then(a.fence_height_m.total_cmp(&b.fence_height_m))
            .then(a.length_m.total_cmp(&b.length_m))
            .then(i.cmp(&j))
    });
    for (r, &i) in order.iter().enumerate() {
        out[i].rank = Some(r + 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shortest_runs_open_and_closed() {
        let l = vec![5.0; 6];
        let one = |c: &[u32], l: &[f64], need: u64, closed: bool| shortest_run(&[c], l, &[need], closed);
        assert_eq!(one(&[0, 3, 0, 5, 1, 0], &l, 6, false), Some((3, 2)));
        assert_eq!(one(&[0, 3, 0, 5, 1, 0], &l, 9, false), Some((1, 4)));
        assert_eq!(one(&[0, 3, 0, 5, 1, 0], &l, 10, false), None);
        assert_eq!(one(&[4, 0, 0, 0, 0, 5], &l, 9, false), Some((0, 6)));
        assert_eq!(one(&[4, 0, 0, 0, 0, 5], &l, 9, true), Some((5, 2)));
        // Shorter last stretch wins a tie in counts.
        assert_eq!(one(&[2, 0, 2], &[5.0, 5.0, 1.0], 2, false), Some((2, 1)));
    }

    #[test]
    fn shortest_run_holds_every_models_need() {
        let l = vec![5.0; 6];
        let (a, b): (&[u32], &[u32]) = (&[0, 3, 0, 5, 1, 0], &[4, 0, 0, 0, 1, 1]);
        // Alone, a needs stretch 3 and b stretch 0; together stretches 0 to 3.
        assert_eq!(shortest_run(&[a], &l, &[5], false), Some((3, 1)));
        assert_eq!(shortest_run(&[b], &l, &[4], false), Some((0, 1)));
        assert_eq!(shortest_run(&[a, b], &l, &[5, 4], false), Some((0, 4)));
        // A model that needs nothing does not move the run; closed lines wrap.
        assert_eq!(shortest_run(&[a, b], &l, &[5, 0], false), Some((3, 1)));
        assert_eq!(shortest_run(&[a, b], &l, &[1, 6], true), Some((4, 3)));
        assert_eq!(shortest_run(&[a, b], &l, &[0, 0], false), None);
    }
}
