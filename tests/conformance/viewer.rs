//! `shadowlab view` under a virtual display (xvfb-run), driven by scripts:
//! - turning the camera and the light, zooming, switching the technique and then the backend, with a bad
//!   model file opened between: every screenshot matches what the printed `render` command of the view
//!   renders offline within the suite's cross-backend FLIP bound and shows the moved view, not the
//!   scene's own; the comparison of the soft technique with its reference prints the RMSE `compare`
//!   reports for that view, the inspected frame its counters; the bad file's one-line error is shown and
//!   the viewer goes on;
//! - a hundred switches of technique, setting and backend leave as many buffers and bytes alive on the
//!   device as the first rounds of them did (the largest of three readings on each side: writes in flight
//!   hold staging buffers for a while).
//!
//! Without xvfb-run or a wgpu adapter this prints one line and passes, unless SHADOWLAB_REQUIRE_GPU=1.

use std::path::Path;
use std::process::Command;

use shadow_core::Image;
use shadow_core::image::Rgb8;
use shadow_core::metrics::flip_mean;

/// The suite's bound on the FLIP error between backends' shaded images.
const MAX_FLIP: f64 = 0.02;

fn shadowlab(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_shadowlab")).args(args).output().expect("the binary runs")
}

fn flip(a: &Image<Rgb8>, b: &Image<Rgb8>) -> f64 {
    flip_mean(a, b, &Image::new(a.width(), a.height(), true)).expect("same size")
}

/// Whether the viewer can be tested here: a wgpu adapter and xvfb-run (`what` names the test skipped).
fn can_view(what: &str) -> bool {
    if crate::with_wgpu(what).is_none() {
        return false;
    }
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        let require = std::env::var("SHADOWLAB_REQUIRE_GPU").is_ok_and(|v| v == "1");
        assert!(!require, "SHADOWLAB_REQUIRE_GPU=1 but xvfb-run is missing (apt-get install xvfb xauth)");
        eprintln!("{what} skipped: no xvfb-run");
        return false;
    }
    true
}

/// Runs `shadowlab view` on `scene` with `script` under a virtual display; its standard output and error.
fn view(scene: &str, size: &str, script: &str) -> (String, String) {
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24", env!("CARGO_BIN_EXE_shadowlab")])
        .args(["view", "--scene", scene, "--size", size, "--script", script])
        .output()
        .expect("xvfb-run runs");
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into());
    assert!(out.status.success(), "the viewer failed: {stderr}");
    (stdout, stderr)
}

/// Runs a `shadowlab render` command the viewer printed with its picture written to `out`: the command's
/// arguments as run, the place of `--out`'s value among them, and the picture.
fn render_printed(command: &str, out: &Path) -> (Vec<String>, usize, Image<Rgb8>) {
    let mut args: Vec<String> = command.split_whitespace().skip(1).map(str::to_string).collect();
    let out_at = args.iter().position(|a| a == "--out").expect("--out") + 1;
    args[out_at] = out.display().to_string();
    let run = Command::new(env!("CARGO_BIN_EXE_shadowlab")).args(&args).output().expect("render runs");
    assert!(run.status.success(), "{command}: {}", String::from_utf8_lossy(&run.stderr));
    (args, out_at, Image::<Rgb8>::load_png(out).expect("the render"))
}

#[test]
fn a_scripted_view_matches_its_render_command_on_both_backends() {
    if !can_view("the scripted view") {
        return;
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("viewer");
    std::fs::create_dir_all(&dir).expect("a folder");
    let shot = |n: u32| dir.join(format!("view-{n}.png"));
    let bad = Path::new(env!("CARGO_MANIFEST_DIR")).join("shadow-core/tests/data/bad/nan_position.obj");
    let script = format!(
        "wait 2; orbit 35 -8; light 50 10; zoom 0.85; technique pcss:res=2048; wait 2; screenshot {}; \
         command; compare; scene {}; backend cpu; technique shadow-volume-zfail; wait 1; screenshot {}; command; inspect; quit",
        shot(1).display(),
        bad.display(),
        shot(2).display()
    );
    let (stdout, stderr) = view("cubes", "720x480", &script);
    assert!(stderr.lines().any(|l| l.contains("nan_position.obj")), "the bad file's error: {stderr}");
    // The comparison of pcss, a soft technique, with the area-light reference: scored as `compare` scores
    // it, by RMSE (checked against `compare` on the same view below).
    let scored = stderr.lines().find(|l| l.starts_with("RMSE ")).unwrap_or_else(|| panic!("no RMSE: {stderr}"));
    assert!(scored.contains("against area-light-reference"), "{scored}");
    let rmse: f64 = scored.split(' ').nth(1).and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("{scored}"));
    // The inspected CPU frame's counters: z-fail's volumes.
    let counters = stdout.lines().find(|l| l.starts_with("counters: ")).unwrap_or_else(|| panic!("{stdout}"));
    assert!(counters.contains("silhouette_edges=") && counters.contains("volume_triangles="), "{counters}");
    let commands: Vec<&str> = stdout.lines().filter(|l| l.starts_with("shadowlab render ")).collect();
    assert_eq!(commands.len(), 2, "{stdout}\n{stderr}");
    for (n, command) in (1..).zip(commands) {
        let viewed = Image::<Rgb8>::load_png(shot(n)).expect("the screenshot");
        let (args, out_at, offline) = render_printed(command, &dir.join(format!("render-{n}.png")));
        if n == 1 {
            // `compare` on the view the viewer compared (its reference at the GPU's own pixels, where the
            // viewer's is at the CPU's: a few pixels of the G-buffers differ).
            let report = dir.join("compare-1");
            let mut compare = args.clone();
            compare[0] = "compare".into();
            compare.splice(out_at - 1..=out_at, ["--out-dir".into(), report.display().to_string()]);
            let run = Command::new(env!("CARGO_BIN_EXE_shadowlab")).args(&compare).output().expect("compare runs");
            assert!(run.status.success(), "{compare:?}: {}", String::from_utf8_lossy(&run.stderr));
            let json = std::fs::read_to_string(report.join("report.json")).expect("the report");
            let json: serde_json::Value = serde_json::from_str(&json).expect("json");
            let compared = json["results"][0]["vs_reference"]["rmse"].as_f64().expect("its RMSE");
            eprintln!("pcss RMSE: the viewer's {rmse:.4}, compare's {compared:.4}");
            assert!(rmse > 0.0 && (rmse - compared).abs() <= 0.002, "the viewer's RMSE {rmse}, compare's {compared}");
        }
        assert_eq!((viewed.width(), viewed.height()), (offline.width(), offline.height()), "{command}");
        let error = flip(&viewed, &offline);
        eprintln!("screenshot {n} against its render command: FLIP {error:.5}");
        assert!(error <= MAX_FLIP, "screenshot {n} against `{command}`: FLIP {error:.4}");
        // Not a blank picture: lit and shadowed ground both show.
        let lum = |p: &Rgb8| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]);
        let (dark, bright) = viewed.data().iter().fold((0, 0), |(d, b), p| match lum(p) {
            l if l < 150 => (d + 1, b),
            l if l > 500 => (d, b + 1),
            _ => (d, b),
        });
        let pixels = viewed.data().len();
        assert!(dark * 50 > pixels && bright * 50 > pixels, "screenshot {n}: {dark} dark, {bright} bright");
        // The script moved the view: the scene's own camera and light render another picture.
        let own = dir.join(format!("own-{n}.png"));
        let size = format!("{}x{}", viewed.width(), viewed.height());
        let backend = if n == 1 { "wgpu" } else { "cpu" };
        let technique = if n == 1 { "pcss:res=2048" } else { "shadow-volume-zfail" };
        let own_run = shadowlab(&[
            "render",
            "--scene",
            "cubes",
            "--size",
            &size,
            "--backend",
            backend,
            "--technique",
            technique,
            "--out",
            own.to_str().expect("a path"),
        ]);
        assert!(own_run.status.success(), "{}", String::from_utf8_lossy(&own_run.stderr));
        let own = Image::<Rgb8>::load_png(&own).expect("the render");
        assert!(flip(&viewed, &own) > 5.0 * MAX_FLIP, "screenshot {n} shows the scene's own view");
    }
}

#[test]
fn a_hundred_switches_leave_no_more_alive_on_the_device_than_the_first_rounds() {
    if !can_view("the viewer's switches") {
        return;
    }
    // One round: four switches (technique, setting, backend there and back with another technique).
    let round = "technique shadow-volume-zfail; wait 1; technique shadow-volume-zfail:extrusion=cpu; wait 1; \
                 backend cpu; wait 1; backend wgpu; technique shadow-map; wait 3";
    let rounds = |n| std::iter::repeat_n(round, n).collect::<Vec<_>>().join("; ");
    // Three readings after rounds 2 to 4 and three after rounds 23 to 25: what is alive at one instant
    // includes the staging buffers of writes still in flight, so each side's largest is compared.
    let script = format!(
        "wait 1; {}; memory; {round}; memory; {round}; memory; {}; memory; {round}; memory; {round}; memory; quit",
        rounds(2),
        rounds(19)
    );
    let (stdout, stderr) = view("primitives", "400x300", &script);
    let readings: Vec<[u64; 3]> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("gpu memory: "))
        .map(|l| {
            let n: Vec<u64> = l.split(|c: char| !c.is_ascii_digit()).filter_map(|w| w.parse().ok()).collect();
            [n[0], n[1], n[2]]
        })
        .collect();
    assert_eq!(readings.len(), 6, "{stdout}\n{stderr}");
    let largest = |r: &[[u64; 3]]| [0, 1, 2].map(|k| r.iter().map(|x| x[k]).max().unwrap_or(0));
    let (early, late) = (largest(&readings[..3]), largest(&readings[3..]));
    assert!(
        (0..3).all(|k| late[k] <= early[k]),
        "buffers, buffer bytes, texture bytes: {early:?} early, {late:?} late"
    );
    assert!(!stderr.contains("error"), "{stderr}");
}

/// The timeline on `walker`: stopped at two times by the script, each screenshot matches the render
/// command the viewer prints for it (which names its time) and the two show different poses; the
/// comparison with the reference on the paused pose scores it as posed (a reference of another pose
/// would put the figure's shadow elsewhere); played on, the figure moves.
#[test]
fn the_timeline_stops_plays_and_is_compared_where_it_stands() {
    if !can_view("the viewer's timeline") {
        return;
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("viewer-timeline");
    std::fs::create_dir_all(&dir).expect("a folder");
    let shot = |n: u32| dir.join(format!("view-{n}.png"));
    let script = format!(
        "wait 1; time 1.3; wait 2; screenshot {}; command; compare; time 2.2; wait 2; screenshot {}; command; \
         play; wait 20; screenshot {}; quit",
        shot(1).display(),
        shot(2).display(),
        shot(3).display()
    );
    let (stdout, stderr) = view("walker", "720x480", &script);
    let scored = stderr.lines().find(|l| l.starts_with("mismatch ")).unwrap_or_else(|| panic!("no score: {stderr}"));
    let mismatch: f64 =
        scored.split(['%', ' ']).nth(1).and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("{scored}"));
    assert!(scored.contains("against ray-traced") && mismatch < 0.5, "the paused pose scored {scored}");
    let commands: Vec<&str> = stdout.lines().filter(|l| l.starts_with("shadowlab render ")).collect();
    assert_eq!(commands.len(), 2, "{stdout}\n{stderr}");
    let mut shots = Vec::new();
    for ((n, command), time) in (1..).zip(commands).zip(["--time 1.3 ", "--time 2.2 "]) {
        assert!(command.contains(time), "{command}");
        let viewed = Image::<Rgb8>::load_png(shot(n)).expect("the screenshot");
        let (_, _, offline) = render_printed(command, &dir.join(format!("render-{n}.png")));
        let error = flip(&viewed, &offline);
        assert!(error <= MAX_FLIP, "screenshot {n} against `{command}`: FLIP {error:.4}");
        shots.push(viewed);
    }
    // Another pose moves the figure and its shadow: a good share of the picture changes by far more
    // than the backends ever differ.
    let moved = |a: &Image<Rgb8>, b: &Image<Rgb8>| {
        let far = a.data().iter().zip(b.data()).filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 40));
        far.count() as f64 / a.data().len() as f64
    };
    let played = Image::<Rgb8>::load_png(shot(3)).expect("the screenshot");
    let (stopped, ran) = (moved(&shots[0], &shots[1]), moved(&shots[1], &played));
    eprintln!("pixels changed: {:.2}% between the two times, {:.2}% played on", 100.0 * stopped, 100.0 * ran);
    assert!(stopped > 0.01, "the two times show the same pose");
    assert!(ran > 0.001, "played on, the figure did not move");
}
