//! The end-of-render summary.
/// The end-of-render summary, as a line for people and JSON for scripts.
pub struct Summary {
    pub written: Vec<String>,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// The samples a part holds (`--samples`, `--shard`), when this run wrote a part rather than the frame.
    pub part: Option<(u32, u32)>,
    pub sampler: &'static str,
    /// Where visible surfaces came from: "raster" or "rays".
    pub primary: &'static str,
    /// How rays were traced: "query", "pipeline", or "none" (the preview).
    pub trace: &'static str,
    /// Diffuse interreflection was on.
    pub indirect: bool,
    pub bounces: u32,
    /// Paths per camera sample (`--shading-samples`).
    pub shading_samples: u32,
    pub seed: u64,
    pub seconds: f64,
    pub stats: Option<strata::render::frame::FrameStats>,
    pub device: String,
    pub triangles: usize,
    pub instances: usize,
    /// The exposure the picture was made with, in stops, and whether auto exposure chose it.
    pub exposure: f32,
    pub auto_exposure: bool,
}

impl Summary {
    /// Samples this run rendered per pixel: a part's, or the frame's.
    fn rendered_samples(&self) -> u32 {
        self.part.map_or(self.spp, |(a, b)| b - a)
    }

    /// "16 spp", or for a part "samples 8..16 of 16 spp"; "× 4 paths" where each sample traced more than one.
    fn samples_text(&self) -> String {
        let samples = match self.part {
            Some((a, b)) => format!("samples {a}..{b} of {} spp", self.spp),
            None => format!("{} spp", self.spp),
        };
        match self.shading_samples {
            1 => samples,
            k => format!("{samples} × {k} paths"),
        }
    }

    /// (camera rays, shadow rays, secondary rays).
    fn rays(&self) -> (u64, u64, u64) {
        self.stats.as_ref().map(|s| (s.camera_rays, s.shadow_rays, s.secondary_rays)).unwrap_or((0, 0, 0))
    }

    pub fn line(&self) -> String {
        let (camera, shadow, secondary) = self.rays();
        let render_seconds = self.stats.as_ref().map(|s| s.seconds).unwrap_or(self.seconds).max(1e-9);
        let camera_part = if camera > 0 { format!("{camera} camera + ") } else { String::new() };
        format!(
            "strata: wrote {} ({}x{}, {} {}, {} primary, {} tracing{}{}, {} triangles) on {} in {:.2} s: {:.2} samples/s, \
             {:.2} M rays/s ({camera_part}{} shadow + {} secondary rays)",
            self.written.join(" and "),
            self.width,
            self.height,
            self.samples_text(),
            self.sampler,
            self.primary,
            self.trace,
            if self.indirect { ", indirect diffuse" } else { "" },
            if self.auto_exposure { format!(", auto exposure {:+.2} EV", self.exposure) } else { String::new() },
            self.triangles,
            self.device,
            self.seconds,
            f64::from(self.rendered_samples()) / render_seconds,
            (camera + shadow + secondary) as f64 / render_seconds / 1e6,
            shadow,
            secondary
        )
    }

    pub fn json(&self) -> serde_json::Value {
        let (camera, shadow, secondary) = self.rays();
        let render_seconds = self.stats.as_ref().map(|s| s.seconds).unwrap_or(self.seconds).max(1e-9);
        serde_json::json!({
            "outputs": self.written,
            "width": self.width,
            "height": self.height,
            "spp": self.spp,
            "sampler": self.sampler,
            "primary": self.primary,
            "trace": self.trace,
            "indirect": self.indirect,
            "bounces": self.bounces,
            "shading_samples": self.shading_samples,
            "seed": self.seed,
            "seconds": self.seconds,
            "render_seconds": render_seconds,
            "samples_per_second": f64::from(self.rendered_samples()) / render_seconds,
            "part": self.part.map(|(a, b)| serde_json::json!({ "samples": [a, b] })),
            "camera_rays": camera,
            "shadow_rays": shadow,
            "secondary_rays": secondary,
            "rays_per_second": (camera + shadow + secondary) as f64 / render_seconds,
            "device": self.device,
            "triangles": self.triangles,
            "instances": self.instances,
            "exposure": self.exposure,
            "auto_exposure": self.auto_exposure,
        })
    }
}
