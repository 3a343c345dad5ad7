//! The command line's arguments: the subcommands, the scene and view flags they share, and the checks on
//! them that need no scene (sizes, the adapter flag).

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand};
use shadow_core::FrameInputs;
use shadow_core::assets::FileAccess;
use shadow_core::scene::ShadowUpdate;
use shadow_core::scenes::SceneParams;
use shadowlab::Error;
use shadowlab::setup::{SceneSetup, parse_size};

pub(crate) const EXIT_CODES: &str = "Exit status: 0 on success; 1 when the work fails (a model file that does not \
load, a technique that refuses the light, a file that cannot be written); 2 for a usage error (an unknown \
flag, scene or technique, a bad value). Every failure is one line on standard error.";

#[derive(Parser)]
#[command(
    after_help = EXIT_CODES,
    name = "shadowlab",
    version,
    about = "Real-time shadow techniques on the GPU and on a CPU reference, measured against ray-traced ground truth"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

/// Where and how to look.
#[derive(Args, Clone)]
pub(crate) struct SceneArgs {
    /// A built-in scene (see `shadowlab scenes`) or a model file (.obj, .gltf, .glb, .ply, .ply.gz).
    #[arg(long, default_value = "cylinder")]
    pub(crate) scene: String,
    /// Ground under a model file: plane or none.
    #[arg(long, default_value = "plane", value_parser = ["plane", "none"])]
    pub(crate) ground: String,
    /// Camera override: eye=X,Y,Z,target=X,Y,Z[,fov=DEG].
    #[arg(long)]
    pub(crate) camera: Option<String>,
    /// Light override: spot|directional|point[,pos=X,Y,Z][,target=X,Y,Z][,fov=DEG][,radius=R].
    #[arg(long)]
    pub(crate) light: Option<String>,
    /// Seed for scenes with random placement.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Let a model file name files outside its own folder (absolute paths, '..'); off by default, so a
    /// model cannot read other files on the machine.
    #[arg(long)]
    pub(crate) allow_outside_files: bool,
    /// Pose the scene's animations at this time, in seconds (each clip holds its last key after its end);
    /// without it the scene stands at rest, as built or loaded.
    #[arg(long, value_name = "SECONDS", value_parser = parse_time)]
    pub(crate) time: Option<f32>,
    /// Give every node its own copy of a mesh that other nodes draw too: the scene without instancing,
    /// to measure against (the pictures are the same).
    #[arg(long)]
    pub(crate) unshare: bool,
    /// Give the scene N lights, to measure how a frame grows with them: its first N, or its own and
    /// copies of them turned about the scene's centre.
    #[arg(long, value_name = "N")]
    pub(crate) lights: Option<usize>,
    /// When every light's shadow is built again: every-frame, on-change (when the light or its casters
    /// moved: the scene's own default), every-N (frames) or once.
    #[arg(long, value_name = "POLICY", value_parser = parse_update)]
    pub(crate) shadow_update: Option<ShadowUpdate>,
}

/// A shadow update policy, by name.
fn parse_update(text: &str) -> Result<ShadowUpdate, String> {
    ShadowUpdate::parse(text.trim()).map_err(|e| e.to_string())
}

/// A time in seconds: a finite number.
fn parse_time(text: &str) -> Result<f32, String> {
    text.trim()
        .parse::<f32>()
        .ok()
        .filter(|t| t.is_finite())
        .ok_or_else(|| format!("'{text}' is not a number of seconds"))
}

/// Which techniques, on which backend: what `compare` and `bench` measure.
#[derive(Args, Clone)]
pub(crate) struct TechniqueArgs {
    /// NAME[:key=value,...], repeatable (default: every technique but the references, with default
    /// settings).
    #[arg(long)]
    pub(crate) technique: Vec<String>,
    /// all, or NAME,NAME with default settings.
    #[arg(long)]
    pub(crate) techniques: Option<String>,
    /// Backend: auto, cpu, wgpu or both.
    #[arg(long, default_value = "auto")]
    pub(crate) backend: String,
}

/// How big the view is and where it is rendered.
#[derive(Args, Clone)]
pub(crate) struct ViewArgs {
    /// View size, WxH.
    #[arg(long, default_value = "512x512")]
    pub(crate) size: String,
    /// wgpu adapter by name substring (also SHADOWLAB_ADAPTER); software adapters such as lavapipe only
    /// when named or with --backend wgpu.
    #[arg(long)]
    pub(crate) adapter: Option<String>,
}

impl ViewArgs {
    /// The view size, within the memory budget.
    pub(crate) fn size(&self) -> Result<(u32, u32), Error> {
        let (w, h) = parse_size(&self.size).map_err(|e| Error::Usage(e.to_string()))?;
        check_view_size(w, h)?;
        Ok((w, h))
    }

    /// Refuses an adapter for a backend that uses none.
    pub(crate) fn check_adapter(&self, backend: &str) -> Result<(), Error> {
        match &self.adapter {
            Some(a) if backend == "cpu" => Err(Error::Usage(format!(
                "--adapter {a} names a wgpu adapter, but --backend cpu uses none (use --backend wgpu or both)"
            ))),
            _ => Ok(()),
        }
    }
}

/// Bytes a view pixel takes in the largest job (`compare`: the G-buffer, the reference, one technique's
/// images and maps in flight, the error maps), rounded up from a measured 2048x2048 CPU run.
pub(crate) const BYTES_PER_VIEW_PIXEL: u64 = 400;
/// The memory a view may take.
pub(crate) const VIEW_MEMORY_BUDGET: u64 = 8 << 30;

pub(crate) fn check_view_size(w: u32, h: u32) -> Result<(), Error> {
    let need = u64::from(w) * u64::from(h) * BYTES_PER_VIEW_PIXEL;
    if need > VIEW_MEMORY_BUDGET {
        return Err(Error::Usage(format!(
            "--size {w}x{h} would take about {:.1} GB ({BYTES_PER_VIEW_PIXEL} bytes a pixel); the budget is {} GB, \
             about {} megapixels",
            need as f64 / 1e9,
            VIEW_MEMORY_BUDGET >> 30,
            VIEW_MEMORY_BUDGET / BYTES_PER_VIEW_PIXEL / 1_000_000
        )));
    }
    Ok(())
}

impl SceneArgs {
    pub(crate) fn setup(&self) -> SceneSetup {
        SceneSetup {
            source: self.scene.clone(),
            ground: self.ground == "plane",
            params: SceneParams { light: None, seed: self.seed },
            camera: self.camera.clone(),
            light: self.light.clone(),
            file_access: if self.allow_outside_files { FileAccess::Anywhere } else { FileAccess::ModelFolder },
            time: self.time,
            unshare: self.unshare,
            lights: self.lights,
            shadow_update: self.shadow_update,
        }
    }

    pub(crate) fn frame(&self, view: &ViewArgs) -> Result<(FrameInputs, u32, u32), Error> {
        let (w, h) = view.size()?;
        let scene = self.setup().build()?;
        print_warnings(&scene);
        Ok((FrameInputs::from_first_camera(&scene)?, w, h))
    }

    pub(crate) fn name(&self) -> String {
        Path::new(&self.scene).file_stem().and_then(|s| s.to_str()).unwrap_or(&self.scene).to_string()
    }
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// List the built-in scenes with their triangle counts.
    Scenes {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// List the techniques: description, paper, settings with defaults, backends.
    Techniques {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Mesh statistics of a model file or built-in scene.
    Inspect {
        /// A built-in scene name or a model file.
        target: String,
        /// Let a model file name files outside its own folder.
        #[arg(long)]
        allow_outside_files: bool,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Render one technique: the shaded image and its visibility.
    Render {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        view: ViewArgs,
        /// NAME[:key=value,...].
        #[arg(long, default_value = "shadow-volume-zfail")]
        technique: String,
        /// Backend: auto, cpu, wgpu or both.
        #[arg(long, default_value = "auto")]
        backend: String,
        /// The shaded PNG; the visibility goes beside it as .vis.png.
        #[arg(long, short, default_value = "render.png")]
        out: PathBuf,
    },
    /// Time techniques over frames with the light moving: per-phase median, min and max, and counters.
    Bench {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        view: ViewArgs,
        #[command(flatten)]
        choice: TechniqueArgs,
        /// Measured frames.
        #[arg(long, default_value_t = 20)]
        frames: u32,
        /// Unmeasured frames first.
        #[arg(long, default_value_t = 2)]
        warmup: u32,
        /// Print JSON.
        #[arg(long)]
        json: bool,
        /// Measure the real-time path on the GPU (frames recorded into the bench's own encoder, two in
        /// flight, no waits or read-backs inside a frame) beside the instrumented frames, with their ratio.
        #[arg(long)]
        realtime: bool,
        /// Rebuild every frame what a still scene keeps (the meshes' adjacency, the CPU's ray-casting BVH),
        /// so its cost is measured: the adjacency as its own time, the BVH in the build phase.
        #[arg(long)]
        rebuild: bool,
        /// Play the scene's animations through the frames, a thirtieth of a second apart from --time (or
        /// 0), with its lights where the clip puts them, instead of turning the light; with --realtime,
        /// reports the host's time to pose each frame beside the time to record it.
        #[arg(long)]
        animate: bool,
        /// Repeat over a parameter: res=256,512,... (map side) or tris=10000,100000,... (a sphere of that
        /// many triangles on the ground); writes sweep.csv and sweep.png.
        #[arg(long)]
        sweep: Option<String>,
        /// Output folder for the sweep (default out/bench-SCENE).
        #[arg(long)]
        out_dir: Option<PathBuf>,
        /// What the frames leave out that no pixel shows: all (each light queried within its reach, lights
        /// that reach no pixel skipped, casters outside a light's frustums culled, maps sized by the shadow
        /// atlas), none (every light from every caster over the whole view), or both, side by side.
        #[arg(long, default_value = "all")]
        savings: String,
        /// What moves from frame to frame: lights (they turn about the scene's centre, a quarter turn over
        /// the frames: every light is built each frame) or camera (the lights stand still, each kept as
        /// its update policy says, and the camera turns an eighth of a turn about the point it looks at).
        #[arg(long = "move", default_value = "lights")]
        motion: String,
        /// Every light casts no shadow: the frame the shadows are measured against.
        #[arg(long)]
        no_shadows: bool,
    },
    /// Temporal flicker along a walk, on the CPU: the fraction of the receivers seen at the start whose lit
    /// state changes between consecutive frames as the maps follow the moving camera (the reference's
    /// never does): shimmering and crawling shadow edges.
    Flicker {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        view: ViewArgs,
        /// NAME[:key=value,...], repeatable.
        #[arg(long, required = true)]
        technique: Vec<String>,
        /// Frames along the walk.
        #[arg(long, default_value_t = 60)]
        frames: usize,
        /// Scene units walked per frame, along the view's level direction.
        #[arg(long, default_value_t = 0.05)]
        step: f32,
        /// Degrees turned left per frame.
        #[arg(long, default_value_t = 0.15)]
        turn: f32,
        /// Seconds of the scene's animations per frame, from --time (0: the scene stands still). A point
        /// of a moving scene flickers where the technique's state changes and the reference's does not,
        /// or the other way round.
        #[arg(long, default_value_t = 0.0, value_name = "SECONDS")]
        time_step: f32,
    },
    /// Measure every technique on every built-in scene (errors on both backends, frame times on one
    /// scene) and write the results page.
    Results {
        /// The markdown file to write.
        #[arg(long, short, default_value = "docs/results.md")]
        out: PathBuf,
        /// View size of the error measurements, WxH.
        #[arg(long, default_value = "512x512")]
        size: String,
        /// Backend: both (the default; needs a GPU adapter, lavapipe will do) or cpu.
        #[arg(long, default_value = "both")]
        backend: String,
        /// The scene timed.
        #[arg(long, default_value = "cubes")]
        bench_scene: String,
        /// View size of the timing, WxH.
        #[arg(long, default_value = "1024x768")]
        bench_size: String,
        /// Frames timed.
        #[arg(long, default_value_t = 10)]
        bench_frames: u32,
        /// View size of the outdoor street's perspective-aliasing measurements, WxH.
        #[arg(long, default_value = "1920x1080")]
        outdoor_size: String,
    },
    /// Open a window onto a scene: fly the camera (drag, wheel, WASD), move the light (right drag, arrow
    /// keys, L to turn it), switch scene, backend, technique and settings in the side panel.
    View {
        #[command(flatten)]
        scene: SceneArgs,
        /// NAME[:key=value,...].
        #[arg(long, default_value = "shadow-map")]
        technique: String,
        /// Backend drawing the view: wgpu or cpu.
        #[arg(long, default_value = "wgpu", value_parser = ["wgpu", "cpu"])]
        backend: String,
        /// The window's size, WxH.
        #[arg(long, default_value = "1280x800")]
        size: String,
        /// Steps replayed one per frame before the user's hands, separated by ';' (orbit YAW PITCH,
        /// light YAW PITCH, zoom F, fly F R U, technique SPEC, backend wgpu|cpu, scene NAME|FILE,
        /// wait FRAMES, screenshot FILE.png, command, compare, inspect, memory, quit).
        #[arg(long)]
        script: Option<String>,
    },
    /// Write a scene (built-in or loaded) as glTF (.glb or .gltf) with its materials, textures, camera
    /// and lights.
    Export {
        #[command(flatten)]
        scene: SceneArgs,
        /// The file to write: .glb (one binary file) or .gltf (JSON, with its buffer and PNG images
        /// beside it).
        #[arg(long, short)]
        out: PathBuf,
    },
    /// Every asked-for technique against its reference (ray-traced for hard shadows,
    /// area-light-reference for soft ones): pictures, error maps, a contact sheet, report.md and
    /// report.json.
    Compare {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        view: ViewArgs,
        #[command(flatten)]
        choice: TechniqueArgs,
        /// The reference for every technique, NAME[:key=value,...]: ray-traced or area-light-reference
        /// (default: each technique's own kind's).
        #[arg(long)]
        reference: Option<String>,
        /// Output folder (default out/compare-SCENE).
        #[arg(long)]
        out_dir: Option<PathBuf>,
    },
}

/// Prints what the scene's source got wrong without stopping it loading, one line each.
pub(crate) fn print_warnings(scene: &shadow_core::Scene) {
    for w in scene.warnings() {
        eprintln!("warning: {w}");
    }
}
