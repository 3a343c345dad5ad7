//! Structure-aware fuzzing of the model loaders, on the stable toolchain.
//!
//! `cargo run --release -p shadowlab-fuzz -- [--target obj|ply|ply-gz|gltf|glb|all] [--minutes M] [--seed S]`
//!
//! Each target generates structurally hostile files of its format (see `generate.rs`), writes them to a
//! case folder under the system's temp folder, and loads them with the default options. A finding is any
//! of: a panic (even one the loader catches), a load that takes over ten seconds, an error that is not one
//! line naming the file, a file that names a file outside its folder and loads, or a load that then cannot
//! be staged and assembled into a frame with finite bounds. Findings are copied to `fuzz/findings/` with
//! their seed, which regenerates them (`--seed S` with one iteration: `--cases 1`).

mod generate;
mod rng;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use shadow_core::FrameInputs;
use shadow_core::assets;

/// A generator of one format's cases.
type Generator = fn(&mut rng::Rng) -> generate::Case;

const TARGETS: &[(&str, Generator)] = &[
    ("obj", generate::obj),
    ("ply", generate::ply),
    ("ply-gz", generate::ply_gz),
    ("gltf", generate::gltf),
    ("glb", generate::glb),
];

/// A load slower than this is a hang.
const HANG: Duration = Duration::from_secs(10);

static PANIC: Mutex<Option<String>> = Mutex::new(None);

struct Options {
    targets: Vec<&'static str>,
    minutes: f64,
    cases: Option<u64>,
    seed: u64,
}

fn options() -> Result<Options, String> {
    let mut o = Options { targets: TARGETS.iter().map(|t| t.0).collect(), minutes: 1.0, cases: None, seed: 1 };
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let mut value = || args.next().ok_or_else(|| format!("{flag} needs a value"));
        match flag.as_str() {
            "--target" => {
                let t = value()?;
                o.targets = match TARGETS.iter().find(|x| x.0 == t) {
                    Some(x) => vec![x.0],
                    None if t == "all" => o.targets,
                    None => return Err(format!("unknown target '{t}' (obj, ply, ply-gz, gltf, glb, all)")),
                };
            }
            "--minutes" => o.minutes = value()?.parse().map_err(|_| "--minutes takes a number")?,
            "--cases" => o.cases = Some(value()?.parse().map_err(|_| "--cases takes a whole number")?),
            "--seed" => o.seed = value()?.parse().map_err(|_| "--seed takes a whole number")?,
            "-h" | "--help" => {
                println!(
                    "usage: fuzz [--target obj|ply|ply-gz|gltf|glb|all] [--minutes M per target] [--cases N] [--seed S]"
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown flag {other}")),
        }
    }
    Ok(o)
}

fn main() {
    let o = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    std::panic::set_hook(Box::new(|info| {
        if let Ok(mut p) = PANIC.lock() {
            *p = Some(info.to_string().replace('\n', " "));
        }
    }));
    let root = std::env::temp_dir().join(format!("shadowlab-fuzz-{}", std::process::id()));
    let findings_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("findings");
    let mut total_findings = 0;
    for &name in &o.targets {
        let generate = TARGETS.iter().find(|t| t.0 == name).map(|t| t.1).expect("a listed target");
        total_findings += run_target(name, generate, &o, &root, &findings_dir);
    }
    let _ = std::fs::remove_dir_all(&root);
    std::process::exit(i32::from(total_findings > 0));
}

/// Counts of one target's run.
#[derive(Default)]
struct Tally {
    cases: u64,
    loaded: u64,
    refused: u64,
    findings: u64,
}

fn run_target(name: &str, generate: Generator, o: &Options, root: &Path, findings_dir: &Path) -> u64 {
    let case_dir = root.join(name).join("case");
    std::fs::create_dir_all(case_dir.join("sub")).expect("the fuzz folder");
    // What a model must not reach: files beside its folder.
    std::fs::write(root.join(name).join("outside.bin"), vec![0x41u8; 4096]).expect("outside.bin");
    std::fs::write(root.join(name).join("outside.mtl"), "newmtl red\nKd 1 0 0\n").expect("outside.mtl");

    let started = Instant::now();
    let budget = Duration::from_secs_f64(o.minutes * 60.0);
    let in_case = Arc::new(AtomicU64::new(u64::MAX));
    let done = Arc::new(AtomicBool::new(false));
    let watchdog = {
        let (in_case, done, case_dir, findings) =
            (in_case.clone(), done.clone(), case_dir.clone(), findings_dir.to_path_buf());
        let name = name.to_string();
        std::thread::spawn(move || {
            let mut last = (u64::MAX, Instant::now());
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(200));
                let seed = in_case.load(Ordering::Relaxed);
                if seed != last.0 {
                    last = (seed, Instant::now());
                } else if seed != u64::MAX && last.1.elapsed() > HANG {
                    let kept = keep(&findings, &name, seed, &case_dir);
                    println!("{name}: FINDING seed {seed}: the load ran over {HANG:?} (kept in {})", kept.display());
                    std::process::exit(3);
                }
            }
        })
    };

    let mut t = Tally::default();
    let mut last_report = Instant::now();
    let mut seed = o.seed;
    loop {
        let over = match o.cases {
            Some(n) => t.cases >= n,
            None => started.elapsed() >= budget,
        };
        if over {
            break;
        }
        let case = generate(&mut rng::Rng::new(seed));
        for (file, bytes) in &case.files {
            std::fs::write(case_dir.join(file), bytes).expect("a case file");
        }
        let model = case_dir.join(&case.files[0].0);
        in_case.store(seed, Ordering::Relaxed);
        let problem = check(&model, &case);
        in_case.store(u64::MAX, Ordering::Relaxed);
        match problem {
            Outcome::Loaded => t.loaded += 1,
            Outcome::Refused => t.refused += 1,
            Outcome::Finding(what) => {
                t.findings += 1;
                let kept = keep(findings_dir, name, seed, &case_dir);
                println!("{name}: FINDING seed {seed}: {what} (kept in {})", kept.display());
            }
        }
        t.cases += 1;
        seed = seed.wrapping_add(1);
        if last_report.elapsed() > Duration::from_secs(30) {
            last_report = Instant::now();
            eprintln!("{name}: {} cases, {:.0}/s, {} findings", t.cases, rate(&t, started), t.findings);
        }
    }
    done.store(true, Ordering::Relaxed);
    let _ = watchdog.join();
    println!(
        "{name}: {} cases in {:.1} min ({:.0}/s): {} loaded, {} refused, {} findings",
        t.cases,
        started.elapsed().as_secs_f64() / 60.0,
        rate(&t, started),
        t.loaded,
        t.refused,
        t.findings
    );
    t.findings
}

fn rate(t: &Tally, started: Instant) -> f64 {
    t.cases as f64 / started.elapsed().as_secs_f64().max(1e-9)
}

enum Outcome {
    Loaded,
    Refused,
    Finding(String),
}

fn check(model: &Path, case: &generate::Case) -> Outcome {
    if let Ok(mut p) = PANIC.lock() {
        *p = None;
    }
    let result = assets::load(model);
    if let Some(p) = PANIC.lock().ok().and_then(|mut p| p.take()) {
        return Outcome::Finding(format!("a panic: {p}"));
    }
    match result {
        Err(e) => {
            let msg = e.to_string();
            if msg.contains('\n') || !msg.starts_with(&model.display().to_string()) {
                return Outcome::Finding(format!("an error that is not one line naming the file: {msg:?}"));
            }
            Outcome::Refused
        }
        Ok(_) if case.names_outside => Outcome::Finding("a model naming a file outside its folder loaded".into()),
        Ok(mut scene) => {
            shadow_core::scenes::stage_model(&mut scene, true);
            let b = scene.bounds();
            if !(b.min.is_finite() && b.max.is_finite()) {
                return Outcome::Finding(format!("staged bounds are not finite: {} .. {}", b.min, b.max));
            }
            let camera = scene.cameras().next().map(|(k, _)| k);
            match camera.map(|c| FrameInputs::from_scene(&scene, c)) {
                Some(Ok(_)) => Outcome::Loaded,
                Some(Err(e)) => Outcome::Finding(format!("loaded, but the frame is refused: {e}")),
                None => Outcome::Finding("loaded and staged without a camera".into()),
            }
        }
    }
}

/// Copies a case's files to `findings/<target>-<seed>/`.
fn keep(findings: &Path, name: &str, seed: u64, case_dir: &Path) -> PathBuf {
    let dir = findings.join(format!("{name}-{seed}"));
    let _ = std::fs::create_dir_all(&dir);
    if let Ok(entries) = std::fs::read_dir(case_dir) {
        for e in entries.flatten().filter(|e| e.path().is_file()) {
            let _ = std::fs::copy(e.path(), dir.join(e.file_name()));
        }
    }
    dir
}
