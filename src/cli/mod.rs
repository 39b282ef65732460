//! Command-line arguments (clap) and their dispatch. The library never sees clap types.

/// `println!` that ignores a closed standard output (`talus run ... | head -2`): the run goes on and writes all its
/// files instead of panicking on the broken pipe.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

mod barrier;
mod benches;
mod calibrate;
mod envelope;
mod mesh;
mod profile;
mod progress;
mod run;
mod section;

use clap::{Args, Parser, Subcommand};

/// The simulating commands' overrides of the scenario (`run`, `barrier`, `profile`).
#[derive(Debug, Args)]
pub struct RunControl {
    /// Number of rocks (overrides the scenario; in a 3D scenario every source's count is scaled to it).
    #[arg(long)]
    pub rocks: Option<usize>,
    /// Seed of all random draws (overrides the scenario).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Threads, 1 to 1024 (default: all cores). Results do not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
}

impl RunControl {
    /// Refuses zero rocks, and zero or too many threads.
    pub fn check(&self) -> anyhow::Result<()> {
        if self.rocks == Some(0) {
            anyhow::bail!("--rocks: must be at least 1");
        }
        check_threads_flag(self.threads)
    }

    /// The overrides of a 3D run, with the paths of the first `paths` rocks.
    pub fn overrides(&self, paths: Option<usize>) -> talus::run::RunOverrides {
        talus::run::RunOverrides { rocks: self.rocks, seed: self.seed, threads: self.threads, paths }
    }
}

/// The named models of `paths` (names by [`talus::envelope::model_names`]), each read and resolved, or, with a
/// `site` (its file and path), carried onto it by [`talus::envelope::on_site`] (`talus envelope --site`,
/// `talus barrier --models`); `command` names the command in messages. A value a model carries onto the site (its
/// materials and engine settings) is checked and named in the model's file.
pub fn load_models(
    paths: &[std::path::PathBuf],
    site: Option<(&talus::scenario::ScenarioFile, &std::path::Path)>,
    command: &str,
) -> anyhow::Result<Vec<(String, talus::scenario::Scenario)>> {
    let paths: Vec<&std::path::Path> = paths.iter().map(|p| p.as_path()).collect();
    let mut models = Vec::new();
    for (path, name) in paths.iter().zip(talus::envelope::model_names(&paths)) {
        let model = read_3d(path, command)?;
        let scenario = match site {
            None => model.resolve(path)?,
            Some((site, site_path)) => {
                // What the model carries is checked in its own file, so that a bad value there is not blamed on
                // the site's.
                model.check_carried(path)?;
                talus::envelope::on_site(site, &model, &path.display().to_string())?.resolve(site_path)?
            }
        };
        models.push((name, scenario));
    }
    Ok(models)
}

/// True if the scenario file at `path` is a 2DLM profile scenario (it has a `profile` key).
pub fn is_profile(path: &std::path::Path) -> bool {
    has_top_key(path, "profile")
}

/// True if the TOML file at `path` reads and has the top-level key `key`.
fn has_top_key(path: &std::path::Path, key: &str) -> bool {
    std::fs::read_to_string(path).ok().and_then(|t| t.parse::<toml::Table>().ok()).is_some_and(|t| t.contains_key(key))
}

/// Reads a 3D scenario for `talus COMMAND`; a profile scenario, which fails to read as one, is named as such rather
/// than by its first unknown key.
pub fn read_3d(path: &std::path::Path, command: &str) -> anyhow::Result<talus::scenario::ScenarioFile> {
    talus::scenario::ScenarioFile::read(path).map_err(|e| {
        if !is_profile(path) {
            return e.into();
        }
        anyhow::anyhow!(
            "{}: a 2DLM profile scenario (it has `profile`), while `talus {command}` takes a 3D scenario (with \
             [terrain], as examples/bench_stack.toml)\n  how to fix: run it with `talus profile`, or give a 3D \
             scenario",
            path.display()
        )
    })
}

/// Reads a 2DLM profile scenario for `talus COMMAND`; a 3D scenario, which fails to read as one, is named as such.
pub fn read_profile(path: &std::path::Path, command: &str) -> anyhow::Result<talus::lumped2d::ProfileScenario> {
    talus::lumped2d::ProfileScenario::load(path).map_err(|e| {
        if !has_top_key(path, "terrain") || is_profile(path) {
            return e.into();
        }
        anyhow::anyhow!(
            "{}: a 3D scenario (it has [terrain]), while `talus {command}` takes a 2DLM profile scenario\n  how to \
             fix: run it with `talus run`, or give a profile scenario (examples/profile_bench.toml)",
            path.display()
        )
    })
}

/// An error of running `scenario`, prefixed "running SCENARIO" unless its message names the file already (it
/// printed the path twice).
pub fn running(scenario: &std::path::Path, e: talus::Error) -> anyhow::Error {
    let name = scenario.display().to_string();
    if e.to_string().contains(&name) {
        e.into()
    } else {
        anyhow::Error::from(e).context(format!("running {name}"))
    }
}

/// Refuses `--threads 0` and more than [`talus::parallel::MAX_THREADS`].
pub fn check_threads_flag(threads: Option<usize>) -> anyhow::Result<()> {
    match threads {
        Some(0) => anyhow::bail!("--threads: must be at least 1 (leave it out to use all cores)"),
        Some(n) => Ok(talus::parallel::check_threads("--threads", n)?),
        None => Ok(()),
    }
}

/// Refuses an output file path (`flag`, e.g. `--out`) that is an existing folder, one of `inputs` (the same file
/// by canonical path, so that a command never overwrites what it reads), or, if `extension` is given, whose
/// extension is not that of the file written. Checked before any work.
pub fn check_out_file(
    flag: &str,
    out: &std::path::Path,
    extension: Option<&str>,
    inputs: &[&std::path::Path],
) -> anyhow::Result<()> {
    refuse_folder(flag, out)?;
    refuse_input(flag, out, inputs)?;
    extension.map_or(Ok(()), |e| require_extension(flag, out, e))
}

/// Refuses an output folder path (`flag`, e.g. `--out`) that is an existing file or lies under one, before any
/// work (a command that makes its folder only when it writes found out after its run).
pub fn check_out_folder(flag: &str, out: &std::path::Path) -> anyhow::Result<()> {
    if let Some(file) = out.ancestors().find(|p| p.is_file()) {
        anyhow::bail!(
            "{flag}: {} is a file\n  how to fix: {flag} names a folder to write into: give a new or existing folder",
            file.display()
        );
    }
    Ok(())
}

/// Refuses `out` if it is an existing folder.
fn refuse_folder(flag: &str, out: &std::path::Path) -> anyhow::Result<()> {
    if out.is_dir() {
        anyhow::bail!(
            "{flag}: {} is a folder\n  how to fix: {flag} must be a file path, not a folder: name a file in it",
            out.display()
        );
    }
    Ok(())
}

/// Refuses `out` if it is the same file as one of `inputs`.
fn refuse_input(flag: &str, out: &std::path::Path, inputs: &[&std::path::Path]) -> anyhow::Result<()> {
    let Ok(out_canonical) = std::fs::canonicalize(out) else {
        return Ok(()); // Not there yet: it cannot be an input.
    };
    if inputs.iter().any(|i| std::fs::canonicalize(i).is_ok_and(|c| c == out_canonical)) {
        anyhow::bail!(
            "{flag}: {} is an input file of this command and would be overwritten\n  how to fix: write to another file",
            out.display()
        );
    }
    Ok(())
}

/// Refuses `out` unless its extension is `extension` (any case).
fn require_extension(flag: &str, out: &std::path::Path, extension: &str) -> anyhow::Result<()> {
    let given = out.extension().map(|e| e.to_string_lossy().to_lowercase());
    if given.as_deref() != Some(extension) {
        anyhow::bail!(
            "{flag}: {} does not end in .{extension}, but a .{extension} file is written\n  how to fix: name the file {}",
            out.display(),
            out.with_extension(extension).display()
        );
    }
    Ok(())
}

/// Runs `go` on `threads` threads (all cores when `None`) for the 2DLM commands, whose engine uses rayon's pool.
pub fn with_threads<T: Send>(
    threads: Option<usize>,
    go: impl FnOnce() -> anyhow::Result<T> + Send,
) -> anyhow::Result<T> {
    #[cfg(feature = "parallel")]
    if let Some(n) = threads {
        use anyhow::Context;
        return rayon::ThreadPoolBuilder::new().num_threads(n).build().context("starting the threads")?.install(go);
    }
    #[cfg(not(feature = "parallel"))]
    let _ = threads;
    go()
}

/// talus: open-source rockfall hazard mapping (3D rigid bodies over real terrain, 2D lumped masses on profiles).
#[derive(Debug, Parser)]
#[command(name = "talus", version, about, long_about = None, arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Run(run::RunArgs),
    Profile(profile::ProfileArgs),
    Benches(benches::BenchesArgs),
    Section(section::SectionArgs),
    Mesh(mesh::MeshArgs),
    Barrier(barrier::BarrierArgs),
    Calibrate(calibrate::CalibrateArgs),
    Envelope(envelope::EnvelopeArgs),
}

/// Parses the command line and runs the command.
pub fn main() -> anyhow::Result<()> {
    // A negative number after a flag is its value (`--bench-height-m -20` then gets talus's own "must be positive",
    // not clap's "unexpected argument '-2'"), in every subcommand.
    fn allow_negatives(cmd: clap::Command) -> clap::Command {
        cmd.allow_negative_numbers(true).mut_subcommands(allow_negatives)
    }
    let parsed = allow_negatives(<Cli as clap::CommandFactory>::command())
        .try_get_matches()
        .and_then(|m| <Cli as clap::FromArgMatches>::from_arg_matches(&m));
    let cli = match parsed {
        Ok(c) => c,
        Err(e) => {
            // Help and version go to stdout with exit 0; usage errors exit 2 with clap's message.
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            std::process::exit(code);
        }
    };
    match cli.command {
        Command::Run(a) => run::run(a),
        Command::Profile(a) => profile::run(a),
        Command::Benches(a) => benches::run(a),
        Command::Section(a) => section::run(a),
        Command::Mesh(a) => mesh::run(a),
        Command::Barrier(a) => barrier::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Envelope(a) => envelope::run(a),
    }
}
