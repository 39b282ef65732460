//! Every settings file shipped in `examples/` loads with the reader of the command it is written for, so a key
//! renamed or a check added in the library cannot leave a shipped example that fails on a user's first try.

use std::path::{Path, PathBuf};
use talus::calibrate::config::{CalibrationConfig, ModelKind};

/// The command an example is for.
#[derive(Debug, Clone, Copy)]
enum Kind {
    /// `talus run`, `talus barrier` (a scenario with `[barrier_design]`) or a site of `talus envelope`.
    Scenario,
    /// `talus calibrate --config` on the Tschamut campaign (3DRB).
    Calibration3d,
    /// `talus benches --config`.
    Benches,
    /// `talus profile`.
    Profile,
}

/// Each example with its command; a new example must be listed here.
const EXAMPLES: &[(&str, Kind)] = &[
    ("barrier_tschamut.toml", Kind::Scenario),
    ("bench_stack.toml", Kind::Scenario),
    ("bench_stack_barrier.toml", Kind::Scenario),
    ("benches_quick.toml", Kind::Benches),
    ("calibrated_tschamut.toml", Kind::Scenario),
    ("profile_bench.toml", Kind::Profile),
    ("profile_tyrol.toml", Kind::Profile),
    ("roughness_step.toml", Kind::Scenario),
    ("tschamut.toml", Kind::Scenario),
    ("tschamut_calibrate.toml", Kind::Calibration3d),
    ("tschamut_combined.toml", Kind::Calibration3d),
    ("tschamut_combined_clip.toml", Kind::Calibration3d),
    ("tschamut_combined_level.toml", Kind::Calibration3d),
    ("tschamut_combined_level_loop.toml", Kind::Calibration3d),
    ("tschamut_combined_level_released.toml", Kind::Calibration3d),
    ("tschamut_combined_level_starts.toml", Kind::Calibration3d),
    ("tschamut_combined_level_strata.toml", Kind::Calibration3d),
    ("tschamut_combined_level_tied.toml", Kind::Calibration3d),
    ("tschamut_combined_level_tied_points.toml", Kind::Calibration3d),
    ("tschamut_combined_level_tied_rough.toml", Kind::Calibration3d),
    ("tschamut_combined_level_tied_rough_loop.toml", Kind::Calibration3d),
    ("tschamut_combined_level_tied_rough_rolling.toml", Kind::Calibration3d),
    ("tschamut_combined_level_tied_screened.toml", Kind::Calibration3d),
    ("tschamut_kfold.toml", Kind::Calibration3d),
    ("tschamut_kfold_w1.toml", Kind::Calibration3d),
    ("tschamut_spread.toml", Kind::Calibration3d),
    ("tschamut_spread_loop.toml", Kind::Calibration3d),
    ("tschamut_vegetation.toml", Kind::Calibration3d),
    ("tyrol.toml", Kind::Scenario),
    ("tyrol_site.toml", Kind::Scenario),
];

fn examples_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples")
}

/// Loads `path` as `kind` does, with the checks the command makes before it simulates; the error as text.
fn load(path: &Path, kind: Kind) -> Result<(), String> {
    let source = path.display().to_string();
    let r = match kind {
        Kind::Scenario => talus::scenario::ScenarioFile::read(path).and_then(|f| f.resolve(path)).map(|_| ()),
        Kind::Calibration3d => CalibrationConfig::read(path).and_then(|c| {
            c.validate(&source)?;
            c.check_model_tables(ModelKind::Rigid3d, &source)?;
            c.check_effects(ModelKind::Rigid3d, &source)
        }),
        Kind::Benches => talus::benches::config::StudyConfig::load(path).map(|_| ()),
        Kind::Profile => talus::lumped2d::scenario::ProfileScenario::load(path).map(|_| ()),
    };
    r.map_err(|e| e.to_string())
}

#[test]
fn every_shipped_example_loads_with_the_reader_of_its_command() {
    let mut on_disk: Vec<String> = std::fs::read_dir(examples_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    on_disk.sort();
    let listed: Vec<String> = EXAMPLES.iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(on_disk, listed, "list each example in tests/examples.rs with the command it is for");
    let failures: Vec<String> = EXAMPLES
        .iter()
        .filter_map(|&(name, kind)| load(&examples_dir().join(name), kind).err().map(|e| format!("{name}: {e}")))
        .collect();
    assert!(failures.is_empty(), "examples that no longer load:\n{}", failures.join("\n"));
    // And each starts with a comment that gives the command running it (examples/README.md says so).
    let no_command: Vec<&str> = EXAMPLES
        .iter()
        .map(|&(name, _)| name)
        .filter(|name| {
            let text = std::fs::read_to_string(examples_dir().join(name)).unwrap();
            !text.lines().take_while(|l| l.starts_with('#')).any(|l| l.contains("talus ") || l.contains("cargo run"))
        })
        .collect();
    assert!(no_command.is_empty(), "give the command in the first comment of: {no_command:?}");
}

#[test]
fn the_example_check_catches_a_broken_example() {
    // The check above can fail: an example with a misspelt key is refused by each reader.
    let dir = tempfile::tempdir().unwrap();
    for &(name, kind) in &[
        ("tschamut.toml", Kind::Scenario),
        ("tschamut_combined_level_tied_rough.toml", Kind::Calibration3d),
        ("benches_quick.toml", Kind::Benches),
        ("profile_bench.toml", Kind::Profile),
    ] {
        let text = std::fs::read_to_string(examples_dir().join(name)).unwrap();
        let p = dir.path().join(name);
        std::fs::write(&p, format!("not_a_key = 1\n{text}")).unwrap();
        let err = load(&p, kind).expect_err(name);
        assert!(err.contains("not_a_key"), "{name}: {err}");
    }
}

#[test]
fn every_example_is_on_the_examples_map() {
    // examples/README.md is where a user looks first: each file and folder of `examples/` is named there (in
    // backquotes, as `name`; a Rust example by its name without `.rs`).
    let map = std::fs::read_to_string(examples_dir().join("README.md")).unwrap();
    let missing: Vec<String> = std::fs::read_dir(examples_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "README.md")
        .filter(|n| {
            let name = n.strip_suffix(".rs").unwrap_or(n);
            !(map.contains(&format!("`{name}`")) || map.contains(&format!("`{n}/`")))
        })
        .collect();
    assert!(missing.is_empty(), "name these in examples/README.md: {missing:?}");
}
