//! Scripted input: steps that stand in for a user's hands, one taken per drawn frame, so a run of the
//! viewer can be replayed (and tested without anyone at the window).
//!
//! A script is steps separated by `;` or new lines:
//! `orbit YAW PITCH` and `light YAW PITCH` turn the camera or the light (degrees), `zoom FACTOR`,
//! `fly FORWARD RIGHT UP` (scene units), `technique SPEC`, `backend wgpu|cpu`, `scene NAME|FILE`,
//! `time SECONDS` (stops a scene's animations at that time), `play` and `pause` (its timeline),
//! `wait FRAMES`, `screenshot FILE.png`, `command` (prints the `shadowlab render` command of the view),
//! `memory` (prints the buffers and textures alive on the device), `compare` (compares the view with the
//! reference and prints its score as `compare` scores it; the script waits for it), `inspect` (prints an
//! instrumented frame's counters and lays its first debug view over the view) and `quit`.

use std::path::PathBuf;

/// Every step's verb.
const STEPS: &str = "orbit, light, zoom, fly, technique, backend, scene, time, play, pause, wait, screenshot, command, \
                     memory, compare, inspect, quit";

/// One step.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Turn the camera around its target (degrees).
    Orbit(f32, f32),
    /// Turn the light around the scene's centre (degrees).
    Light(f32, f32),
    /// Scale the camera's distance.
    Zoom(f32),
    /// Move the camera and its target.
    Fly(f32, f32, f32),
    /// Switch the technique.
    Technique(String),
    /// Switch the backend (`wgpu` or `cpu`).
    Backend(String),
    /// Open a scene.
    Scene(String),
    /// Stop the scene's animations at this time (seconds).
    Time(f32),
    /// Play (`true`) or pause the scene's animations.
    Play(bool),
    /// Draw this many frames before the next step.
    Wait(u32),
    /// Write the view as PNG.
    Screenshot(PathBuf),
    /// Print the `shadowlab render` command of the view.
    Command,
    /// Print the buffers and textures alive on the device.
    Memory,
    /// Compare the view with its reference and print the score (mismatch, or RMSE for a soft technique).
    Compare,
    /// Inspect an instrumented frame: print its counters, show its debug views.
    Inspect,
    /// Close the viewer.
    Quit,
}

/// Parses a script (see the module notes).
///
/// # Errors
/// The first step that does not parse, named with its position.
pub fn parse(text: &str) -> Result<Vec<Step>, String> {
    let steps = text.split([';', '\n']).map(str::trim).filter(|s| !s.is_empty());
    steps.enumerate().map(|(i, s)| step(s).map_err(|why| format!("--script step {} '{s}': {why}", i + 1))).collect()
}

fn step(text: &str) -> Result<Step, String> {
    let (verb, rest) = text.split_once(char::is_whitespace).unwrap_or((text, ""));
    let rest = rest.trim();
    let numbers = |n: usize| -> Result<Vec<f32>, String> {
        let v: Vec<f32> = rest
            .split_whitespace()
            .map(|w| w.parse::<f32>().ok().filter(|x| x.is_finite()).ok_or(format!("'{w}' is not a number")))
            .collect::<Result<_, _>>()?;
        if v.len() == n { Ok(v) } else { Err(format!("takes {n} numbers")) }
    };
    let word = || if rest.is_empty() { Err("takes a value".to_string()) } else { Ok(rest.to_string()) };
    Ok(match verb {
        "orbit" => numbers(2).map(|v| Step::Orbit(v[0], v[1]))?,
        "light" => numbers(2).map(|v| Step::Light(v[0], v[1]))?,
        "zoom" => match numbers(1)?[0] {
            f if f > 0.0 => Step::Zoom(f),
            _ => return Err("the factor must be above 0".into()),
        },
        "fly" => numbers(3).map(|v| Step::Fly(v[0], v[1], v[2]))?,
        "technique" => Step::Technique(word()?),
        "backend" => match rest {
            "wgpu" | "cpu" => Step::Backend(rest.into()),
            _ => return Err("wgpu or cpu".into()),
        },
        "scene" => Step::Scene(word()?),
        "time" => match numbers(1)?[0] {
            t if t >= 0.0 => Step::Time(t),
            _ => return Err("the time must be 0 or more".into()),
        },
        "play" if rest.is_empty() => Step::Play(true),
        "pause" if rest.is_empty() => Step::Play(false),
        "wait" => Step::Wait(rest.parse().map_err(|_| format!("'{rest}' is not a frame count"))?),
        "screenshot" => Step::Screenshot(word()?.into()),
        "command" if rest.is_empty() => Step::Command,
        "memory" if rest.is_empty() => Step::Memory,
        "compare" if rest.is_empty() => Step::Compare,
        "inspect" if rest.is_empty() => Step::Inspect,
        "quit" if rest.is_empty() => Step::Quit,
        "command" | "memory" | "compare" | "inspect" | "quit" | "play" | "pause" => {
            return Err("takes nothing".into());
        }
        _ => return Err(format!("unknown step ({STEPS})")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_parse_and_bad_ones_are_named() {
        let steps = parse(
            "orbit 30 -10; zoom 0.5\nfly 1 0 0.5; technique pcss:light_size=0.2; backend cpu; wait 3;\
                           screenshot out/a.png; command; time 1.5; play; pause; quit",
        )
        .unwrap();
        assert_eq!(steps.len(), 12);
        assert_eq!(steps[8..11], [Step::Time(1.5), Step::Play(true), Step::Play(false)]);
        assert_eq!(steps[0], Step::Orbit(30.0, -10.0));
        assert_eq!(steps[3], Step::Technique("pcss:light_size=0.2".into()));
        assert_eq!(steps[11], Step::Quit);
        for (bad, why) in [
            ("orbit 30", "takes 2 numbers"),
            ("orbit 30 x", "'x' is not a number"),
            ("zoom 0", "above 0"),
            ("backend vulkan", "wgpu or cpu"),
            ("jump", "unknown step"),
            ("wait -1", "frame count"),
            ("time -2", "0 or more"),
            ("pause 3", "takes nothing"),
            ("technique", "takes a value"),
        ] {
            let e = parse(&format!("wait 1; {bad}")).unwrap_err();
            assert!(e.contains("step 2") && e.contains(why), "{bad}: {e}");
        }
    }
}
