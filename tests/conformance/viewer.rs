//! `shadowlab view` under a virtual display (xvfb-run): a script turns the camera and the light, zooms,
//! switches the technique and then the backend, writing a screenshot and printing the `render` command
//! of the view after each; every screenshot matches what that command renders offline within the
//! suite's cross-backend FLIP bound, and shows the moved view, not the scene's own. Without xvfb-run or
//! a wgpu adapter this prints one line and passes, unless SHADOWLAB_REQUIRE_GPU=1.

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

#[test]
fn a_scripted_view_matches_its_render_command_on_both_backends() {
    if crate::with_wgpu("the viewer").is_none() {
        return;
    }
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        let require = std::env::var("SHADOWLAB_REQUIRE_GPU").is_ok_and(|v| v == "1");
        assert!(!require, "SHADOWLAB_REQUIRE_GPU=1 but xvfb-run is missing (apt-get install xvfb)");
        eprintln!("the viewer skipped: no xvfb-run");
        return;
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("viewer");
    std::fs::create_dir_all(&dir).expect("a folder");
    let shot = |n: u32| dir.join(format!("view-{n}.png"));
    let script = format!(
        "wait 2; orbit 35 -8; light 50 10; zoom 0.85; technique pcss:res=2048; wait 2; screenshot {}; \
         command; backend cpu; technique shadow-volume-zfail; wait 1; screenshot {}; command; quit",
        shot(1).display(),
        shot(2).display()
    );
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24", env!("CARGO_BIN_EXE_shadowlab")])
        .args(["view", "--scene", "cubes", "--size", "720x480", "--script", &script])
        .output()
        .expect("xvfb-run runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "the viewer failed: {stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let commands: Vec<&str> = stdout.lines().filter(|l| l.starts_with("shadowlab render ")).collect();
    assert_eq!(commands.len(), 2, "{stdout}\n{stderr}");
    for (n, command) in (1..).zip(commands) {
        let viewed = Image::<Rgb8>::load_png(shot(n)).expect("the screenshot");
        let rendered = dir.join(format!("render-{n}.png"));
        let mut args: Vec<String> = command.split_whitespace().skip(1).map(str::to_string).collect();
        let out_at = args.iter().position(|a| a == "--out").expect("--out") + 1;
        args[out_at] = rendered.display().to_string();
        let run = Command::new(env!("CARGO_BIN_EXE_shadowlab")).args(&args).output().expect("render runs");
        assert!(run.status.success(), "{command}: {}", String::from_utf8_lossy(&run.stderr));
        let offline = Image::<Rgb8>::load_png(&rendered).expect("the render");
        assert_eq!((viewed.width(), viewed.height()), (offline.width(), offline.height()), "{command}");
        let error = flip(&viewed, &offline);
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
