//! The bench design study (`talus benches`) on a reduced study that runs in seconds: the seed paper's findings as
//! tests, the Wilson interval, the output format, determinism, and the `profile`, `benches` and `section` commands.

use std::path::Path;
use std::process::Command;
use std::sync::OnceLock;
use talus::benches::*;

/// 2 face angles × 3 widths × 3 seeds; 60 2DLM runs per mass (180 per configuration) and 12 3DRB runs per
/// configuration and seed.
fn reduced() -> StudyConfig {
    StudyConfig {
        face_angles_deg: vec![60.0, 75.0],
        bench_widths_m: vec![4.0, 7.0, 10.0],
        repeats: 3,
        seed: 11,
        lumped2d: talus::benches::config::Lumped2dSpec { runs: 60, ..Default::default() },
        rigid3d: talus::benches::config::Rigid3dSpec { runs: 12, ..Default::default() },
        ..Default::default()
    }
}

fn study() -> &'static StudyResult {
    static STUDY: OnceLock<StudyResult> = OnceLock::new();
    STUDY.get_or_init(|| run_study(&reduced(), &|_, _, _| {}).unwrap())
}

fn config_index(r: &StudyResult, angle: f64, width: f64) -> usize {
    r.configurations.iter().position(|c| c.face_angle_deg == angle && c.bench_width_m == width).unwrap()
}

/// Counts on the first bench and counted rocks, pooled over seeds and the given configurations.
fn first_bench(r: &StudyResult, model: Model, configs: &[(f64, f64)]) -> (usize, usize) {
    configs.iter().fold((0, 0), |(k, n), &(a, w)| {
        let (per_bench, total) = r.pooled(model, config_index(r, a, w));
        (k + per_bench[1], n + total)
    })
}

fn fraction(r: &StudyResult, model: Model, configs: &[(f64, f64)]) -> f64 {
    let (k, n) = first_bench(r, model, configs);
    k as f64 / n as f64
}

#[test]
fn every_rock_is_counted_once() {
    let r = study();
    assert_eq!(r.configurations.len(), 6);
    for c in &r.cells {
        let runs = r.runs(c.model);
        assert_eq!(c.counted() + c.left + c.crest, runs, "{c:?}");
        assert_eq!(c.stop_reasons.values().sum::<usize>(), runs);
        assert!(c.counted() >= runs * 3 / 4, "{c:?}");
    }
    assert_eq!(r.rocks.len(), 3 * 6 * (3 * 60 + 12));
}

#[test]
fn capture_grows_with_bench_width() {
    let r = study();
    for angle in [60.0, 75.0] {
        let f: Vec<f64> = [4.0, 7.0, 10.0].iter().map(|&w| fraction(r, Model::Lumped2d, &[(angle, w)])).collect();
        assert!(f[2] > f[0] && f[1] >= f[0] - 0.02 && f[2] >= f[1] - 0.02, "2DLM {angle}°: {f:?}");
        // 3DRB is noisy with 36 rocks per width: compare the narrowest and the widest.
        let (narrow, wide) =
            (fraction(r, Model::Rigid3d, &[(angle, 4.0)]), fraction(r, Model::Rigid3d, &[(angle, 10.0)]));
        assert!(wide > narrow, "3DRB {angle}°: 4 m {narrow}, 10 m {wide}");
    }
}

#[test]
fn steeper_faces_capture_more_on_the_first_bench() {
    let r = study();
    for w in [4.0, 7.0, 10.0] {
        let (f60, f75) = (fraction(r, Model::Lumped2d, &[(60.0, w)]), fraction(r, Model::Lumped2d, &[(75.0, w)]));
        assert!(f75 >= f60, "2DLM {w} m: 60° {f60}, 75° {f75}");
    }
    let all = |a: f64| [(a, 4.0), (a, 7.0), (a, 10.0)];
    assert!(fraction(r, Model::Lumped2d, &all(75.0)) > fraction(r, Model::Lumped2d, &all(60.0)));
    let (f60, f75) = (fraction(r, Model::Rigid3d, &all(60.0)), fraction(r, Model::Rigid3d, &all(75.0)));
    assert!(f75 > f60, "3DRB over all widths: 60° {f60}, 75° {f75}");
}

#[test]
fn lumped_reruns_vary_less_than_rigid_reruns() {
    let r = study();
    let mean_sd = |model: Model| {
        let sds: Vec<f64> = (0..r.configurations.len())
            .map(|c| {
                let f: Vec<f64> = r.cells_of(model, c).filter_map(|cell| cell.fraction(1)).collect();
                assert_eq!(f.len(), 3);
                Spread::of(&f).unwrap().sd
            })
            .collect();
        sds.iter().sum::<f64>() / sds.len() as f64
    };
    let (lm, rb) = (mean_sd(Model::Lumped2d), mean_sd(Model::Rigid3d));
    assert!(lm < rb, "mean sd between seeds: 2DLM {lm}, 3DRB {rb}");
}

#[test]
fn wilson_interval_known_values() {
    // Reference values: Wilson (1927) score interval at 95 %, e.g. Newcombe (1998) Table I.
    let check = |k, n, lo: f64, hi: f64| {
        let (a, b) = wilson_interval(k, n, Z_95).unwrap();
        assert!((a - lo).abs() < 5e-5 && (b - hi).abs() < 5e-5, "{k}/{n}: ({a}, {b}) vs ({lo}, {hi})");
    };
    check(5, 10, 0.2366, 0.7634);
    check(0, 10, 0.0, 0.2775);
    check(10, 10, 0.7225, 1.0);
    check(81, 263, 0.2553, 0.3662);
    check(15, 148, 0.0624, 0.1605);
    assert_eq!(wilson_interval(0, 0, Z_95), None);
    let (lo, hi) = wilson_interval(270, 300, Z_95).unwrap();
    assert!(lo < 0.9 && 0.9 < hi && hi < 1.0);
}

#[test]
fn outputs_have_the_specified_columns_and_add_up() {
    let r = study();
    let dir = tempfile::tempdir().unwrap();
    let records = [
        HistoricRecord { bench_height_m: 20.0, bench_width_m: 8.0, face_angle_deg: 62.0, runout_m: 3.0 },
        HistoricRecord { bench_height_m: 20.0, bench_width_m: 8.0, face_angle_deg: 72.0, runout_m: 9.5 },
        HistoricRecord { bench_height_m: 21.0, bench_width_m: 6.0, face_angle_deg: 75.0, runout_m: 5.0 },
        HistoricRecord { bench_height_m: 40.0, bench_width_m: 9.0, face_angle_deg: 60.0, runout_m: 1.0 },
    ];
    let summary = write_outputs(r, Some(&records), dir.path()).unwrap();
    let text = std::fs::read_to_string(dir.path().join("capture.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "model,face_angle_deg,bench_width_m,bench,runs,captured_fraction,ci_low,ci_high");
    assert_eq!(
        CAPTURE_COLUMNS.join(","),
        "model,face_angle_deg,bench_width_m,bench,runs,captured_fraction,ci_low,ci_high"
    );
    let rows: Vec<Vec<String>> = lines.map(|l| l.split(',').map(String::from).collect()).collect();
    assert_eq!(rows.len(), 2 * 6 * 6);
    for group in rows.chunks(6) {
        let benches: Vec<&str> = group.iter().map(|r| r[3].as_str()).collect();
        assert_eq!(benches, ["1", "2", "3", "4", "5", "0"]);
        let sum: f64 = group.iter().map(|r| r[5].parse::<f64>().unwrap()).sum();
        assert!((sum - 1.0).abs() < 1e-5, "{group:?}");
        for row in group {
            assert_eq!(row.len(), 8);
            let (f, lo, hi): (f64, f64, f64) =
                (row[5].parse().unwrap(), row[6].parse().unwrap(), row[7].parse().unwrap());
            assert!(lo <= f && f <= hi, "{row:?}");
        }
    }
    assert_eq!(rows[0][0], "2DLM");
    assert_eq!(rows[36][0], "3DRB");
    // The records with a bench height within 5 m of 20 m: 3 of 4.
    assert_eq!(summary.records.as_ref().unwrap().used, 3);
    let rec = std::fs::read_to_string(dir.path().join("records_capture.csv")).unwrap();
    assert!(rec.lines().any(|l| l == "all,8.5,3,2,0.666667,0.207660,0.938508"), "{rec}");
    let fig = std::fs::read_to_string(dir.path().join("figure7_first_bench_75deg.svg")).unwrap();
    assert!(fig.contains("historic records (n=2)") && fig.contains("Modified Ritchie width 8.5 m"));
    assert!(fig.contains("90 % retention target"));
    for f in &summary.outputs {
        assert!(dir.path().join(f).exists(), "{f}");
    }
    assert!(summary.outputs.iter().any(|f| f == "per_bench/figure6_60deg_4m.svg"));
    assert!(summary.outputs.iter().any(|f| f == "spread.csv"));
    // Headline at the Modified Ritchie width: interpolated between 7 and 10 m for both models.
    let h: Vec<&HeadlinePoint> =
        summary.first_bench_at_modified_ritchie.iter().filter(|h| h.model != "records").collect();
    assert_eq!(h.len(), 4);
    assert!(h.iter().all(|h| h.interpolated_between_m == Some([7.0, 10.0])));
    // Its interval spans both widths' Wilson intervals (capture grows with the width), from capture.csv.
    for p in &h {
        let ci = |w: &str| {
            let row = rows.iter().find(|r| {
                r[0] == p.model && r[1].parse::<f64>().unwrap() == p.face_angle_deg && r[2] == w && r[3] == "1"
            });
            let r = row.unwrap();
            (r[6].parse::<f64>().unwrap(), r[7].parse::<f64>().unwrap())
        };
        let (lo, hi) = (ci("7").0.min(ci("10").0), ci("7").1.max(ci("10").1));
        assert!((p.ci_low.unwrap() - lo).abs() < 1e-6 && (p.ci_high.unwrap() - hi).abs() < 1e-6, "{p:?}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["config"]["lumped2d"]["runs"], 60);
    assert!(json["timings"][1]["rocks_per_second"].as_f64().unwrap() > 0.0);
    let report = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(report.contains("interpolated linearly between the simulated widths 7 m and 10 m"), "{report}");
    assert!(report.contains("## Spread between seeds"));
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mut c = StudyConfig {
        face_angles_deg: vec![60.0],
        bench_widths_m: vec![5.0, 9.0],
        lumped2d: talus::benches::config::Lumped2dSpec { runs: 50, ..Default::default() },
        rigid3d: talus::benches::config::Rigid3dSpec { runs: 6, ..Default::default() },
        ..Default::default()
    };
    c.threads = 1;
    let one = run_study(&c, &|_, _, _| {}).unwrap();
    c.threads = 2;
    let two = run_study(&c, &|_, _, _| {}).unwrap();
    assert_eq!(one.rocks, two.rocks);
    assert_eq!(one.cells, two.cells);
}

// ---- The command line ----

fn talus(args: &[&str], cwd: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_talus")).args(args).current_dir(cwd).output().unwrap()
}

fn repo(p: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p).display().to_string()
}

#[test]
fn cli_profile_runs_a_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let out = talus(
        &[
            "profile",
            &repo("examples/profile_bench.toml"),
            "--out",
            "prof",
            "--rocks",
            "40",
            "--seed",
            "3",
            "--threads",
            "2",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("40 rocks") && stdout.contains("bench 1"), "{stdout}");
    for f in ["endpoints.csv", "envelopes.csv", "collectors.csv", "profile.csv", "summary.json"] {
        assert!(dir.path().join("prof").join(f).exists(), "{f}");
    }
    let out = talus(&["profile", &repo("examples/profile_bench.toml"), "--out", "p2", "--rocks", "0"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    // A material no segment has (a calibrated zone carried to a design profile without it): warned about, kept in
    // summary.json.
    let text = std::fs::read_to_string(repo("examples/profile_bench.toml")).unwrap();
    std::fs::write(dir.path().join("zoned.toml"), text + "\n[materials.zone1]\npreset = \"floor_all\"\n").unwrap();
    let out = talus(&["profile", "zoned.toml", "--out", "zoned", "--rocks", "20"], dir.path());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let warning = "[materials.zone1] is defined but no segment of the profile has it";
    assert!(err.contains(&format!("warning: {warning}")), "{err}");
    let summary = std::fs::read_to_string(dir.path().join("zoned/summary.json")).unwrap();
    assert!(summary.contains(warning), "{summary}");
    // The section example: a profile cut from the Tyrol DEM.
    let out = talus(&["profile", &repo("examples/profile_tyrol.toml"), "--out", "tyrol", "--rocks", "20"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn cli_benches_runs_a_small_study_with_records() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("records.csv"),
        "# synthetic rows for the test\nbench_height_m,bench_width_m,face_angle_deg,runout_m\n20,7,60,2.5\n20,8,60,9\n",
    )
    .unwrap();
    let out = talus(
        &[
            "benches",
            "--out",
            "b",
            "--face-angles-deg",
            "60",
            "--bench-widths-m",
            "5,9",
            "--runs-2dlm",
            "30",
            "--runs-3drb",
            "6",
            "--seed",
            "5",
            "--records",
            "records.csv",
            "--threads",
            "2",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("Modified Ritchie width 8.5 m") && stdout.contains("records"), "{stdout}");
    let b = dir.path().join("b");
    for f in ["capture.csv", "rocks.csv", "records_capture.csv", "summary.json", "report.md", "figure7_first_bench.svg"]
    {
        assert!(b.join(f).exists(), "{f}");
    }
    let capture = std::fs::read_to_string(b.join("capture.csv")).unwrap();
    assert_eq!(capture.lines().count(), 1 + 2 * 2 * 6);
    // A config file, overridden by a flag.
    std::fs::write(
        dir.path().join("study.toml"),
        "face_angles_deg = [75.0]\nbench_widths_m = [6.0]\n[rigid3d]\nruns = 0\n",
    )
    .unwrap();
    let out = talus(&["benches", "--config", "study.toml", "--out", "c", "--runs-2dlm", "20"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let capture = std::fs::read_to_string(dir.path().join("c/capture.csv")).unwrap();
    assert!(capture.lines().skip(1).all(|l| l.starts_with("2DLM,75,6,") && l.contains(",60,")), "{capture}");
}

#[test]
fn cli_benches_names_a_bad_config_key() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("study.toml"), "bench_height_m = 20.0\n[lumped2d]\nrunz = 10\n").unwrap();
    let out = talus(&["benches", "--config", "study.toml", "--out", "x"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("runz") && err.contains("study.toml:3"), "{err}");
    let out = talus(&["benches", "--out", "x", "--face-angles-deg", "60,95"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("face_angles_deg[1]"));
    assert!(!dir.path().join("x").exists());
    // An --out that is a file is refused before the study runs (it ran the whole study first).
    std::fs::write(dir.path().join("a_file"), "x").unwrap();
    let out = talus(&["benches", "--out", "a_file"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--out: a_file is a file"));
}

#[test]
fn cli_section_cuts_the_bench_stack() {
    let dir = tempfile::tempdir().unwrap();
    let out =
        talus(&["mesh", "bench", "--out", "stack.obj", "--face-angle-deg", "60", "--bench-width-m", "7"], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = talus(
        &["section", "stack.obj", "--line", "0,30,150,30", "--spacing-m", "0.5", "--out", "sec/profile.csv"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let p = talus::lumped2d::Profile::from_csv_path(&dir.path().join("sec/profile.csv")).unwrap();
    let bench = talus::lumped2d::Profile::from_bench(&talus::terrain::BenchGeometry::default()).unwrap();
    for x in [0.0, 15.0, 25.0, 33.3, 77.7, 149.0] {
        let (a, b) = (p.z_at(x).unwrap(), bench.z_at(x).unwrap());
        assert!((a - b).abs() < 0.3, "x {x}: section {a}, bench {b}");
    }
    assert_eq!(p.material_names(), &["floor".to_string(), "face".to_string()]);
    let out = talus(&["section", "stack.obj", "--line", "0,30,500,30", "--out", "bad.csv"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing at"), "{}", String::from_utf8_lossy(&out.stderr));
    let out = talus(&["section", "stack.obj", "--line", "0,30,5", "--out", "bad.csv"], dir.path());
    assert_eq!(out.status.code(), Some(2));
}
