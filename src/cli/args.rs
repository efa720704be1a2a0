//! The command line's options, with the parsers that check them as they are read.
use clap::Args;
use std::path::PathBuf;
use strata::scene::settings::MAX_IMAGE_SIDE as MAX_SIDE;
use strata::scene::settings::{MAX_BOUNCES, MAX_EXPOSURE_STOPS, MAX_SHADING_SAMPLES, MAX_SPP};

/// The most frames one run of --frames renders.
pub const MAX_FRAMES: u64 = 100_000;

#[derive(Args)]
pub struct BenchArgs {
    /// Samples timed per case (the median is reported), after one warm-up.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub samples: u32,
    /// The scene file of the "cornell" cases.
    #[arg(long, value_name = "FILE", default_value = "scenes/cornell.toml")]
    pub scene: PathBuf,
    /// The second scene of the frame benchmark.
    #[arg(long, value_name = "FILE", default_value = "scenes/showcase.toml")]
    pub showcase: PathBuf,
    /// The morphing asset of the deform benchmark (its first clip animates morph weights).
    #[arg(long, value_name = "FILE", default_value = "tests/data/gltf-samples/MorphStressTest.gltf")]
    pub morph: PathBuf,
    /// Which benchmark: gbuffer (pass times and bump cost), frame (whole distributed-ray-traced frames, the
    /// ray-query ceiling, scaling and memory), scale-out (checkpoint and merge costs), deform (the per-sample cost
    /// of skins and animated morph weights), or all.
    #[arg(
        long,
        value_name = "WHICH",
        default_value = "all",
        value_parser = ["all", "gbuffer", "frame", "scale-out", "deform"]
    )]
    pub only: String,
    /// Samples per pixel of the frame benchmark.
    #[arg(long, value_name = "N", default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub spp: u32,
    /// Image size of the frame benchmark (its scaling runs use a quarter, half and all of it).
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Run under the Khronos validation layer and exit non-zero on any error or warning: a check that the
    /// benchmark itself is sound (the layer slows everything, so the figures mean nothing then).
    #[arg(long)]
    pub validate: bool,
    /// Use this device: its index in `strata info`, or part of its name.
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<String>,
}

#[derive(Args)]
pub struct CheckArgs {
    /// Check this device: its index in `strata info`, or part of its name.
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<String>,
    /// How the cases trace rays: query, pipeline, or auto (ray queries where the device has them).
    #[arg(long, value_name = "HOW", default_value = "auto", value_parser = parse_trace)]
    pub trace: strata::scene::settings::Trace,
    /// Where the reports go: results.csv, failures.csv, results.json, summary.md, report.html, and a directory
    /// per case with its pictures and log.
    #[arg(long, value_name = "DIR", default_value = "check-report")]
    pub out: PathBuf,
    /// Only the cases whose names match this regular expression (e.g. 'golden/' or '^optics/penumbra$').
    #[arg(long, value_name = "REGEX")]
    pub cases: Option<String>,
    /// What this device is known to do: a TOML file of [[expect]] and [[allow]] entries (docs/check.md), or the
    /// failures.csv of an earlier run as a baseline. A listed failure passes the run as ExpectedFail; a listed
    /// case that passes is an UnexpectedPass.
    #[arg(long, value_name = "FILE")]
    pub expectations: Option<PathBuf>,
    /// Also write JUnit XML here (device, driver, Vulkan API, layer and strata versions as properties).
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Cases run side by side, each in its own process.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub jobs: u32,
    /// Run every Nth case from the Kth (K in 1..=N): one shard of a CI matrix.
    #[arg(long, value_name = "K/N", value_parser = parse_fraction)]
    pub fraction: Option<(usize, usize)>,
    /// A short suite (under 30 s on a 2-core lavapipe machine): a few cases of each kind, and the canaries.
    #[arg(long)]
    pub quick: bool,
    /// Make the outputs of the golden and AOV cases the new goldens (the old files are kept as .old), for the
    /// device this runs on. Needs a goldens directory: the repository's check/goldens, or --goldens DIR.
    #[arg(long)]
    pub bless: bool,
    /// Render each golden case at other seeds and set its perceptual thresholds from the spread measured, with
    /// a margin (written to the goldens' goldens.toml).
    #[arg(long)]
    pub calibrate: bool,
    /// The goldens directory [default: the repository's check/goldens when this binary was built in it, else
    /// the copy embedded in the binary].
    #[arg(long, value_name = "DIR")]
    pub goldens: Option<PathBuf>,
    /// Seconds a case may run before it is killed and reported as Timeout.
    #[arg(long, value_name = "SECONDS", default_value_t = 300, value_parser = clap::value_parser!(u64).range(1..=86400))]
    pub timeout: u64,
    /// List the cases (with --quick and --cases applied) and exit.
    #[arg(long)]
    pub list: bool,
    /// Run one case in this process and write its result (what the suite starts each child with).
    #[arg(long, value_name = "CASE", hide = true)]
    pub child: Option<String>,
    #[arg(long, hide = true, default_value_t = 1)]
    pub attempt: u32,
    /// Include the hidden cases that crash, hang, flake and fail on purpose (the suite's own tests).
    #[arg(long, hide = true)]
    pub test_cases: bool,
}

#[derive(Args)]
pub struct GpuArgs {
    /// Run under the Khronos validation layer (synchronization validation and best practices on) and print
    /// its messages; exit non-zero if it reports any error or warning.
    #[arg(long)]
    pub validate: bool,
    /// Use this device: its index in `strata info`, or part of its name (e.g. "llvmpipe").
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<String>,
}

#[derive(Args)]
pub struct RenderArgs {
    /// The scene: a glTF 2.0 file (.gltf or .glb), or a scene file (.toml, see docs/scene-format.md) that names
    /// one and adds camera, lights, materials, motion and render settings. Several render one after another on
    /// one device and one set of pipelines (thumbnails of a library); -o then needs {name}, which becomes each
    /// file's name without its extension. A scene that fails is reported and the others still render; the
    /// exit status is then non-zero.
    #[arg(required = true, num_args = 1.., value_name = "SCENE")]
    pub scenes: Vec<PathBuf>,
    /// Output file, .png (exposed, tone-mapped, 8-bit sRGB) or .exr (linear radiance, 32-bit float)
    /// [default: the scene file's render.output].
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also write the linear radiance to this OpenEXR file (with the --aov layers, if any).
    #[arg(long, value_name = "FILE")]
    pub exr: Option<PathBuf>,
    /// Denoise the picture with Intel Open Image Denoise, guided by the first-hit albedo and normal: -o gets the
    /// denoised image, an --exr keeps the noisy one as its `noisy` layer. The library is loaded at run time:
    /// `scripts/setup.sh --denoiser` installs it (from the pyoidn wheel).
    #[arg(long, conflicts_with = "preview")]
    pub denoise: bool,
    /// Also write each frame's camera to this JSON file: the image size, the intrinsics K (pixels, OpenCV's axes),
    /// yfov (radians, as glTF), world_from_camera (glTF's axes) and the OpenCV-axes pose, near/far, the frame's
    /// time and exposure. Numbered per frame as -o is (a run of # sets the digits); {name} as in -o.
    #[arg(long, value_name = "FILE.json")]
    pub camera_json: Option<PathBuf>,
    /// Image size in pixels, each side 1 to 16384 [default: the scene file's, else 960x540].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Samples per pixel, 1 to 65536: each is a G-buffer pass at its own lens point, shutter time and sub-pixel
    /// jitter plus an accumulation pass [default: the scene file's, else 16].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: Option<u32>,
    /// How sample points are placed: regular (strata centres; aliases), random, jittered (one random point in
    /// each of n x n strata, Cook 1984), multi-jittered (Kensler 2013; also stratified in x and in y), sobol
    /// (Owen-scrambled Sobol, Burley 2020; best at powers of two) [default: the scene file's, else multi-jittered].
    #[arg(long, value_name = "NAME", value_parser = parse_sampler)]
    pub sampler: Option<strata::scene::settings::SamplerKind>,
    /// Seed of every random choice; the same scene, options and seed give the same bits on the same device
    /// [default: the scene file's, else 0].
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Thin-lens aperture radius in metres, 0 to 1000; 0 is a pinhole (everything sharp) [default: the scene's
    /// camera].
    #[arg(long, value_name = "METRES", value_parser = parse_aperture, allow_hyphen_values = true)]
    pub aperture: Option<f32>,
    /// Distance in metres of the plane in focus, 0 to 1e9 [default: the scene's camera].
    #[arg(long, value_name = "METRES", value_parser = parse_focus, allow_hyphen_values = true)]
    pub focus: Option<f32>,
    /// Shutter interval in seconds; motion during it blurs. OPEN:CLOSE with equal times is a still frame; each
    /// time within ±1e9 s [default: the scene file's, else 0:0].
    #[arg(long, value_name = "OPEN:CLOSE", value_parser = parse_shutter)]
    pub shutter: Option<(f32, f32)>,
    /// Exposure in stops, -64 to 64: the PNG's radiance is scaled by 2^EV before tone mapping; or `auto`, which maps the
    /// picture's log-average luminance to middle grey (0.18, as photographic tone reproduction does) and prints
    /// the value it chose (also in --json). The default, 0, shows radiance as it is: right for scenes made in
    /// relative units (strata's own), too bright for glTF lights in physical units (a 6830-lux sun) [default:
    /// the scene file's, else 0].
    #[arg(long, value_name = "EV|auto", allow_hyphen_values = true, value_parser = parse_exposure, conflicts_with = "ev100")]
    pub exposure: Option<ExposureArg>,
    /// Photographic exposure value at ISO 100 (sunny day 15, overcast 12, indoors 7): radiance × 1 / (1.2 × 2^EV100),
    /// the saturation-based exposure physically based renderers use (Lagarde and de Rousiers, "Moving Frostbite
    /// to PBR", 2014). For glTF scenes whose lights are in physical units. From -60 to 60 (the same span of stops
    /// as --exposure).
    #[arg(long, value_name = "EV100", allow_hyphen_values = true, value_parser = parse_ev100)]
    pub ev100: Option<f32>,
    /// Tone map for the PNG: clamp (none), or filmic (an ACES fit) [default: the scene file's, else filmic].
    #[arg(long, value_name = "NAME", value_parser = parse_tone_map)]
    pub tone_map: Option<strata::scene::settings::ToneMap>,
    /// Where each sample's visible surface comes from: raster (the G-buffer pass; fast, but each sample's pixel
    /// jitter and lens point are shared by all pixels, so fine regular patterns can show moiré) or rays (a ray
    /// per pixel with its own jitter and lens point: noise instead of moiré, the reference the raster mode is
    /// tested against; the shutter time is still shared per sample) [default: the scene file's, else raster].
    #[arg(long, value_name = "MODE", value_parser = parse_primary)]
    pub primary: Option<strata::scene::settings::Primary>,
    /// How rays are traced: query (VK_KHR_ray_query in a compute shader), pipeline (a ray-tracing pipeline,
    /// VK_KHR_ray_tracing_pipeline: NVIDIA H100/H200 have only this), or auto (ray queries where the device has
    /// them, else a pipeline). Both run the same shading code; `strata info` shows which a device has
    /// [default: the scene file's, else auto].
    #[arg(long, value_name = "HOW", value_parser = parse_trace)]
    pub trace: Option<strata::scene::settings::Trace>,
    /// Also follow paths by the diffuse lobe: light bouncing between diffuse surfaces (Kajiya 1986), up to
    /// --bounces times with Russian roulette, on top of Cook's effects. Slower and noisier; off by default, or as
    /// the scene file's `indirect` says.
    #[arg(long, overrides_with = "no_indirect")]
    pub indirect: bool,
    /// Cook's effects alone, where the scene file's `indirect = true` turns diffuse interreflection on (the last
    /// of --indirect and --no-indirect wins).
    #[arg(long, overrides_with = "indirect")]
    pub no_indirect: bool,
    /// Most bounces after the visible surface, 0 to 16: gloss and translucency rays, and diffuse ones with
    /// --indirect. 0 is direct light alone; 3 sees through a glass sphere [default: the scene file's, else 3].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=MAX_BOUNCES as i64))]
    pub bounces: Option<u32>,
    /// Paths traced from each sample's visible surface, 1 to 256, each with its own light, BSDF and bounce
    /// samples (stratified over spp x N); the sample's pixel jitter, lens point and shutter time are shared, so
    /// the G-buffer is drawn spp times, not spp x N. Raise it where the noise is in the lighting (area lights,
    /// soft shadows, gloss, an environment), not in edges, depth of field or motion blur: 16 spp x 4 costs less
    /// than 64 spp and, there, is as smooth [default: the scene file's, else 1].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_SHADING_SAMPLES as i64))]
    pub shading_samples: Option<u32>,
    /// What pixels no surface covers show: a linear RGB colour R,G,B (also what escaping rays see without an
    /// environment), environment (the --environment as the camera sees it), or transparent (alpha 0: the PNG
    /// is RGBA with straight alpha, the EXR premultiplied; the scene is lit as before) [default: the scene
    /// file's, else the environment when there is one, else 0.02,0.02,0.025].
    #[arg(long, value_name = "R,G,B|environment|transparent", value_parser = parse_background)]
    pub background: Option<BackgroundArg>,
    /// Light the scene with an environment: an equirectangular (latitude-longitude) Radiance .hdr or OpenEXR
    /// image, or `studio` for a generated one (soft dome, warm key, cool fill). It is importance-sampled like any
    /// light (with MIS against the BSDF) and is what escaping rays see; its centre column faces -Z [default:
    /// the scene file's [environment], else none].
    #[arg(long, value_name = "FILE|studio")]
    pub environment: Option<PathBuf>,
    /// Turn the environment about +Y by this many degrees (counter-clockwise seen from above).
    #[arg(long, value_name = "DEGREES", allow_hyphen_values = true, value_parser = parse_finite)]
    pub environment_rotation: Option<f32>,
    /// Scale the environment's radiance, 0 to 1e9.
    #[arg(long, value_name = "X", value_parser = parse_intensity)]
    pub environment_intensity: Option<f32>,
    /// Also write G-buffer channels (comma-separated): normal, geometric-normal, albedo, depth, height, position,
    /// emission, material; and the labels a dataset needs: instance (the glTF node index + 1 each pixel's centre
    /// sees, 0 for nothing), semantic (its node's class: extras.category_id or the scene file's [[semantic]]) and
    /// motion (forward flow in pixels to one frame, 1/--fps, later). With an .exr they
    /// are layers of the EXR (raw values); with -o x.png each is a PNG beside it, x.<name>.png (normals as ½+½n,
    /// depth and height scaled to their range, labels as colours). docs/outputs.md says what each holds.
    #[arg(long, value_name = "LIST", value_parser = parse_aovs)]
    pub aov: Option<AovList>,
    /// Look from an orbit around the scene (or --target): azimuth THETA about +Y in degrees from +Z towards +X
    /// (0 looks along -Z), elevation PHI above the horizontal, and the DISTANCE in metres [default distance: far
    /// enough that the whole scene fits the image with a 10% margin]. Replaces the scene's camera.
    #[arg(long, value_name = "THETA,PHI[,DISTANCE]", value_parser = parse_orbit, allow_hyphen_values = true)]
    pub orbit: Option<Orbit>,
    /// The point the camera looks at (with --orbit or --turntable, or alone: the default orbit around it)
    /// [default: the centre of the scene's bounds].
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    pub target: Option<[f32; 3]>,
    /// Vertical field of view in degrees of the (perspective) camera [default: the scene camera's; 45 for a camera
    /// strata places].
    #[arg(long, value_name = "DEGREES", value_parser = parse_yfov)]
    pub yfov: Option<f32>,
    /// Render N views around +Y (a turntable, N from 1 to 100000): the orbit's azimuth steps by 360/N degrees from --orbit's (or 0),
    /// written as -o's name with the view's number, 1 to N (thumb.png: thumb.0001.png ...; a run of # in -o
    /// sets the digits: thumb.##.png). One device, one upload, one set of pipelines for all of them.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub turntable: Option<u32>,
    /// Render the frames A to B (inclusive, at most 100000 of them) of the scene's animation, frame k at time
    /// k / --fps, each with its own shutter (--shutter-angle), written as -o's name with the frame's number.
    #[arg(long, value_name = "A..B", value_parser = parse_frames)]
    pub frames: Option<(u32, u32)>,
    /// Frames per second of --frames and --time, 0.001 to 1000.
    #[arg(long, value_name = "F", default_value_t = 24.0, value_parser = parse_fps)]
    pub fps: f32,
    /// Which animation clip plays, by name or index (`strata info FILE` lists them); one clip plays at a time, the
    /// first unless this or the scene file's `animation` names another.
    #[arg(long, value_name = "NAME|INDEX", value_parser = parse_animation)]
    pub animation: Option<strata::scene::animation::AnimationChoice>,
    /// The KHR_materials_variants variant whose materials the meshes take, by name (`strata info FILE` lists
    /// them) [default: the scene file's `variant`, else the file's default materials].
    #[arg(long, value_name = "NAME")]
    pub variant: Option<String>,
    /// Render one frame at time T seconds of the animation (its shutter as --shutter-angle says): the same picture
    /// as the frame of --frames at that time.
    #[arg(long, value_name = "T", value_parser = parse_time, allow_hyphen_values = true)]
    pub time: Option<f32>,
    /// The shutter of --frames and --time as a fraction of a frame, in degrees: 180 opens it for half a frame
    /// (film's usual motion blur), 0 is a still frame.
    #[arg(long, value_name = "DEGREES", default_value_t = 180.0, value_parser = parse_shutter_angle)]
    pub shutter_angle: f32,
    /// Render only samples A to B-1 of the frame's --spp and write a part (-o must be .exr) for `strata merge`:
    /// 0..32 and 32..64 are the halves of 64, and merge to the bytes one render of 64 makes.
    #[arg(long, value_name = "A..B", value_parser = parse_sample_range, help_heading = "Scale-out")]
    pub samples: Option<(u32, u32)>,
    /// Render shard K of N (1-based): one frame's samples (written as a part for `strata merge`), or with
    /// --frames/--turntable the frames, each shard a share of them. `auto` takes K and N from the array job of
    /// Slurm (SLURM_ARRAY_TASK_ID); `auto/N` from a Kubernetes Indexed Job (JOB_COMPLETION_INDEX) or AWS Batch
    /// (AWS_BATCH_JOB_ARRAY_INDEX), which do not say N.
    #[arg(long, value_name = "K/N|auto", value_parser = strata::partial::shard::parse_shard, help_heading = "Scale-out")]
    pub shard: Option<strata::partial::shard::ShardSpec>,
    /// Save the render's sums to FILE (a part, .exr, written atomically) every --checkpoint-every seconds, and
    /// on Ctrl-C or SIGTERM (then exit 75). Run the same command again to go on from it: a render killed at any
    /// moment loses at most one interval and ends with the bytes an uninterrupted one makes. Removed once the
    /// output is written.
    #[arg(long, value_name = "FILE", help_heading = "Scale-out")]
    pub checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints, from 0.01 to 86400 (a day).
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0, value_parser = parse_checkpoint_interval, help_heading = "Scale-out")]
    pub checkpoint_every: f32,
    /// Go on from this checkpoint (or part) of the same render instead of starting from zero.
    #[arg(long, value_name = "FILE", help_heading = "Scale-out")]
    pub resume: Option<PathBuf>,
    /// Render the fast raster preview (one sample, simple shading, no ray queries) instead.
    #[arg(long)]
    pub preview: bool,
    /// No progress bar and no summary line (errors and warnings still go to stderr).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the summary as one JSON object on stdout (for scripts).
    #[arg(long)]
    pub json: bool,
    /// Let the glTF read files outside its own directory (absolute paths, ".."). Network URIs are never fetched.
    #[arg(long)]
    pub allow_any_uri: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

impl RenderArgs {
    /// What the command line says of the camera (None where it is silent): laid over the scene's.
    /// How the command line asks to see the scene.
    pub fn view(&self) -> strata::scene::framing::View {
        strata::scene::framing::View {
            orbit: self.orbit,
            target: self.target.map(glam::Vec3::from_array),
            yfov_degrees: self.yfov,
            turntable: self.turntable.is_some(),
        }
    }

    pub fn camera_overrides(&self) -> strata::scene::settings::CameraOverrides {
        strata::scene::settings::CameraOverrides {
            aperture_radius: self.aperture,
            focus_distance: self.focus,
            shutter: self.shutter,
        }
    }

    /// What the command line says of the render settings (None where it is silent): laid over the defaults and
    /// the scene file's.
    pub fn overrides(&self) -> strata::scene::settings::SettingsOverrides {
        strata::scene::settings::SettingsOverrides {
            width: self.size.map(|s| s.0),
            height: self.size.map(|s| s.1),
            spp: self.spp,
            sampler: self.sampler,
            seed: self.seed,
            background: match self.background {
                Some(BackgroundArg::Colour(rgb)) => Some(glam::Vec3::from_array(rgb)),
                _ => None,
            },
            backdrop: self.background.map(|b| match b {
                BackgroundArg::Colour(_) => strata::scene::settings::Backdrop::Colour,
                BackgroundArg::Environment => strata::scene::settings::Backdrop::Environment,
                BackgroundArg::Transparent => strata::scene::settings::Backdrop::Transparent,
            }),
            exposure: match (self.exposure, self.ev100) {
                (Some(ExposureArg::Stops(ev)), _) => Some(ev),
                (_, Some(ev100)) => Some(ev100_stops(ev100)),
                _ => None,
            },
            tone_map: self.tone_map,
            primary: self.primary,
            indirect: if self.indirect { Some(true) } else { self.no_indirect.then_some(false) },
            bounces: self.bounces,
            shading_samples: self.shading_samples,
            trace: self.trace,
            output: self.output.clone(),
        }
    }
}

#[derive(Args)]
pub struct InfoArgs {
    /// A scene (.gltf, .glb or .toml) to describe instead of the devices: its meshes, materials, cameras, lights
    /// and animation clips (the names and indices --animation takes).
    #[arg(value_name = "SCENE")]
    pub scene: Option<std::path::PathBuf>,
    /// Also print the devices' validation messages (creates an instance with the layer when installed).
    #[arg(long)]
    pub validate: bool,
}

pub fn parse_animation(text: &str) -> Result<strata::scene::animation::AnimationChoice, String> {
    if text.is_empty() {
        return Err("name an animation clip, or give its index".into());
    }
    Ok(strata::scene::animation::AnimationChoice::parse(text))
}

pub fn parse_sampler(text: &str) -> Result<strata::scene::settings::SamplerKind, String> {
    strata::scene::settings::SamplerKind::parse(text).map_err(|e| e.to_string())
}

pub fn parse_trace(text: &str) -> Result<strata::scene::settings::Trace, String> {
    strata::scene::settings::Trace::parse(text).map_err(|e| e.to_string())
}

pub fn parse_primary(text: &str) -> Result<strata::scene::settings::Primary, String> {
    strata::scene::settings::Primary::parse(text).map_err(|e| e.to_string())
}

pub fn parse_tone_map(text: &str) -> Result<strata::scene::settings::ToneMap, String> {
    strata::scene::settings::ToneMap::parse(text).map_err(|e| e.to_string())
}

pub fn parse_shutter(text: &str) -> Result<(f32, f32), String> {
    let (open, close) = text.split_once(':').ok_or_else(|| format!("\"{text}\" is not OPEN:CLOSE, e.g. 0:0.25"))?;
    let time = |s: &str| -> Result<f32, String> { parse_time(s) };
    let (open, close) = (time(open)?, time(close)?);
    if close < open {
        return Err(format!("the shutter closes ({close}) before it opens ({open})"));
    }
    Ok((open, close))
}

pub fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| format!("\"{text}\" is not WIDTHxHEIGHT, e.g. 960x540"))?;
    let side = |s: &str| -> Result<u32, String> {
        let v: u32 = s.trim().parse().map_err(|_| format!("\"{s}\" is not a whole number of pixels"))?;
        if v == 0 || v > MAX_SIDE {
            return Err(format!("{v} pixels is outside 1..={MAX_SIDE}"));
        }
        Ok(v)
    };
    Ok((side(w)?, side(h)?))
}

/// The parsed `--aov` list (a newtype: clap reads a bare `Vec` as a multi-value option).
#[derive(Clone)]
pub struct AovList(pub Vec<strata::render::aov::Aov>);

pub fn parse_aovs(text: &str) -> Result<AovList, String> {
    strata::render::aov::Aov::parse_list(text).map(AovList).map_err(|e| e.to_string())
}

pub fn parse_rgb(text: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("\"{text}\" is not R,G,B (three numbers)"));
    }
    let mut rgb = [0.0; 3];
    for (slot, part) in rgb.iter_mut().zip(parts) {
        let v: f32 = part.trim().parse().map_err(|_| format!("\"{part}\" is not a number"))?;
        if !v.is_finite() || v < 0.0 {
            return Err(format!("{v} is not a finite non-negative radiance"));
        }
        *slot = v;
    }
    Ok(rgb)
}

/// What `--background` says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BackgroundArg {
    Colour([f32; 3]),
    Environment,
    Transparent,
}

pub fn parse_background(text: &str) -> Result<BackgroundArg, String> {
    match text {
        "environment" => Ok(BackgroundArg::Environment),
        "transparent" => Ok(BackgroundArg::Transparent),
        _ => parse_rgb(text).map(BackgroundArg::Colour).map_err(|e| format!("{e}; or say environment or transparent")),
    }
}

pub fn parse_finite(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("\"{text}\" is not a finite number")),
    }
}

/// `K/N` with 1 ≤ K ≤ N.
pub fn parse_fraction(text: &str) -> Result<(usize, usize), String> {
    let (k, n) = text.split_once('/').ok_or_else(|| format!("{text:?}: expected K/N, e.g. 2/4"))?;
    let k: usize = k.trim().parse().map_err(|_| format!("{text:?}: K must be a whole number"))?;
    let n: usize = n.trim().parse().map_err(|_| format!("{text:?}: N must be a whole number"))?;
    if n == 0 || k == 0 || k > n {
        return Err(format!("{text:?}: K must be 1 to N (the first shard is 1/{n})", n = n.max(1)));
    }
    Ok((k, n))
}

pub use strata::scene::camera::Orbit;

/// `THETA,PHI` or `THETA,PHI,DISTANCE` (degrees, degrees, metres).
pub fn parse_orbit(text: &str) -> Result<Orbit, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if !(2..=3).contains(&parts.len()) {
        return Err(format!("\"{text}\" is not THETA,PHI or THETA,PHI,DISTANCE"));
    }
    let number = |s: &str| -> Result<f32, String> {
        s.parse::<f32>().ok().filter(|v| v.is_finite()).ok_or_else(|| format!("\"{s}\" is not a finite number"))
    };
    let (theta, phi) = (number(parts[0])?, number(parts[1])?);
    if phi.abs() > 90.0 {
        return Err(format!("the elevation {phi} must be between -90 and 90 degrees"));
    }
    let distance = match parts.get(2) {
        Some(d) => {
            let d = number(d)?;
            if d <= 0.0 {
                return Err(format!("the distance {d} must be more than 0 metres"));
            }
            Some(d)
        }
        None => None,
    };
    Ok(Orbit { theta_degrees: theta, phi_degrees: phi, distance })
}

/// `X,Y,Z`, finite.
pub fn parse_point(text: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("\"{text}\" is not X,Y,Z"));
    }
    let mut p = [0.0; 3];
    for (slot, part) in p.iter_mut().zip(parts) {
        *slot = part
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("\"{part}\" is not a finite number"))?;
    }
    Ok(p)
}

pub fn parse_yfov(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if v > 0.0 && v < 180.0 => Ok(v),
        _ => Err(format!("\"{text}\" is not a field of view between 0 and 180 degrees")),
    }
}

/// A number within `lo..=hi`; the error names the span and what the number is.
fn parse_within(text: &str, lo: f32, hi: f32, what: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("\"{text}\" is not {what} from {lo} to {hi}")),
    }
}

/// Times of the animation and the shutter: ±1e9 s (31 years) keeps every time sum finite and exact enough.
pub const MAX_TIME_SECONDS: f32 = 1e9;

pub fn parse_time(text: &str) -> Result<f32, String> {
    parse_within(text, -MAX_TIME_SECONDS, MAX_TIME_SECONDS, "a time in seconds")
}

pub fn parse_fps(text: &str) -> Result<f32, String> {
    parse_within(text, 0.001, 1000.0, "a frame rate")
}

pub fn parse_aperture(text: &str) -> Result<f32, String> {
    parse_within(text, 0.0, 1000.0, "an aperture radius in metres")
}

pub fn parse_focus(text: &str) -> Result<f32, String> {
    parse_within(text, 0.0, 1e9, "a focus distance in metres")
}

pub fn parse_intensity(text: &str) -> Result<f32, String> {
    parse_within(text, 0.0, 1e9, "an intensity")
}

pub fn parse_shutter_angle(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if (0.0..=360.0).contains(&v) => Ok(v),
        _ => Err(format!("\"{text}\" is not a shutter angle from 0 to 360 degrees")),
    }
}

/// `A..B` with A ≤ B (frame numbers, inclusive).
/// `A..B`, samples A to B-1.
pub fn parse_sample_range(text: &str) -> Result<(u32, u32), String> {
    strata::partial::sample_set::parse_range(text).map_err(|e| e.to_string())
}

pub fn parse_frames(text: &str) -> Result<(u32, u32), String> {
    let (a, b) = text.split_once("..").ok_or_else(|| format!("\"{text}\" is not A..B, e.g. 1..48"))?;
    let frame = |s: &str| s.trim().parse::<u32>().map_err(|_| format!("\"{s}\" is not a frame number"));
    let (a, b) = (frame(a)?, frame(b)?);
    if b < a {
        return Err(format!("the last frame {b} comes before the first {a}"));
    }
    // In 64 bits: 0..4294967295 is 2^32 frames, which 32 bits would count as 0.
    let count = u64::from(b) - u64::from(a) + 1;
    if count > MAX_FRAMES {
        return Err(format!("{count} frames is more than one run renders ({MAX_FRAMES})"));
    }
    Ok((a, b))
}

/// What `--exposure` says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ExposureArg {
    Stops(f32),
    Auto,
}

pub fn parse_exposure(text: &str) -> Result<ExposureArg, String> {
    if text == "auto" {
        return Ok(ExposureArg::Auto);
    }
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= MAX_EXPOSURE_STOPS => Ok(ExposureArg::Stops(v)),
        _ => Err(format!(
            "\"{text}\" is not a number of stops between -{MAX_EXPOSURE_STOPS} and {MAX_EXPOSURE_STOPS}, or auto"
        )),
    }
}

/// The most `--ev100` says either way: its stops ([`ev100_stops`]) stay within --exposure's.
pub const MAX_EV100: f32 = 60.0;

pub fn parse_ev100(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= MAX_EV100 => Ok(v),
        _ => Err(format!("\"{text}\" is not an EV100 between -{MAX_EV100} and {MAX_EV100} (sunny day 15, indoors 7)")),
    }
}

/// The longest interval between checkpoints: a day. (Far longer would overflow a Duration; 1e30 did.)
pub const MAX_CHECKPOINT_SECONDS: f32 = 86400.0;

pub fn parse_checkpoint_interval(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if (0.01..=MAX_CHECKPOINT_SECONDS).contains(&v) => Ok(v),
        _ => Err(format!("\"{text}\" is not a number of seconds from 0.01 to {MAX_CHECKPOINT_SECONDS} (a day)")),
    }
}

/// The exposure in stops of a photographic EV100: 1 / (1.2 × 2^EV100).
pub fn ev100_stops(ev100: f32) -> f32 {
    -(1.2f32.log2()) - ev100
}

#[derive(Args)]
pub struct MergeArgs {
    /// The parts: .exr files written by `strata render --samples`, `--shard` or `--checkpoint`, in any order.
    #[arg(value_name = "PART", required = true)]
    pub parts: Vec<PathBuf>,
    /// The frame: .png (display-encoded) or .exr (linear), the bytes one render of every sample writes. With
    /// --partial, a part (.exr) holding the samples of all the parts.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Also write the linear frame to this .exr (as `strata render --exr` does).
    #[arg(long, value_name = "FILE")]
    pub exr: Option<PathBuf>,
    /// Merge some parts into a bigger part instead of a frame: samples may be missing (a merge tree for many
    /// machines), none may be twice.
    #[arg(long)]
    pub partial: bool,
    /// Remove the parts once the output is written.
    #[arg(long)]
    pub remove_parts: bool,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}
