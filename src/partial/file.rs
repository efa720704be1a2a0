//! The part file: an OpenEXR whose layers are the fixed-point sums (each 64-bit count as two 32-bit channels,
//! `sum_hi.*` and `sum_lo.*`) and the sample count per pixel (`samples.Y`), and whose header says what the part
//! belongs to (strata version, device, scene, settings, seed), which samples it holds, and how the frame is
//! resolved, so that `strata merge` needs nothing but the parts. Written atomically like every output.
use super::{PartialSums, SampleSet};
use crate::scene::settings::{ToneMap, MAX_EXPOSURE_STOPS, MAX_IMAGE_SIDE, MAX_SPP};
use crate::shaders::constants::{SUM_FRACTION_BITS, SUM_MAX_SAMPLE_LOG2};
use anyhow::{anyhow, bail, Context as _, Result};
use std::path::Path;

/// What a part belongs to: parts merge only when every field agrees.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Provenance {
    pub strata_version: String,
    /// The device, its driver and the way it traced: other devices may round differently.
    pub device: String,
    /// FNV-1a of the scene as rendered (after the command line's camera and environment options).
    pub scene: String,
    /// FNV-1a of the settings that change the picture (size, samples, sampler, bounces, look, ...).
    pub settings: String,
    pub seed: u64,
}

impl Provenance {
    /// The first field on which two parts disagree, with both values.
    pub fn difference(&self, other: &Provenance) -> Option<(&'static str, String, String)> {
        let fields = [
            ("strata version", &self.strata_version, &other.strata_version),
            ("device", &self.device, &other.device),
            ("scene", &self.scene, &other.scene),
            ("settings", &self.settings, &other.settings),
        ];
        if self.seed != other.seed {
            return Some(("seed", self.seed.to_string(), other.seed.to_string()));
        }
        fields.into_iter().find(|(_, a, b)| a != b).map(|(name, a, b)| (name, a.clone(), b.clone()))
    }
}

/// How the merged frame is resolved: the display settings of the render the parts came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartLook {
    pub exposure: f32,
    pub tone_map: ToneMap,
    pub transparent: bool,
    pub auto_exposure: bool,
}

/// A part as read from or written to disk.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    pub provenance: Provenance,
    pub look: PartLook,
    pub sums: PartialSums,
}

const FORMAT: &str = "strata-part-1";
const SUM_CHANNELS: [&str; 4] = ["R", "G", "B", "A"];

/// Writes `part` to `path` (an .exr) atomically.
pub fn write_part(path: &Path, part: &Part) -> anyhow::Result<()> {
    use exr::prelude::*;
    if crate::output::OutputFormat::from_path(path)? != crate::output::OutputFormat::Exr {
        bail!("{}: a part of a frame is written as an .exr (for strata merge)", path.display());
    }
    let sums = &part.sums;
    sums.check_fits(sums.width, sums.height, sums.spp)?;
    let pixels = sums.width as usize * sums.height as usize;
    let mut channels = Vec::with_capacity(9);
    for (c, name) in SUM_CHANNELS.iter().enumerate() {
        let column =
            |shift: u32| -> Vec<u32> { (0..pixels).map(|p| (sums.counts[p * 4 + c] >> shift) as u32).collect() };
        channels.push(AnyChannel::new(Text::from(format!("sum_hi.{name}").as_str()), FlatSamples::U32(column(32))));
        channels.push(AnyChannel::new(Text::from(format!("sum_lo.{name}").as_str()), FlatSamples::U32(column(0))));
    }
    channels.push(AnyChannel::new(Text::from("samples.Y"), FlatSamples::U32(vec![sums.samples.len(); pixels])));
    let channels = AnyChannels::sort(SmallVec::from_vec(channels));
    let mut attributes = LayerAttributes::default();
    let p = &part.provenance;
    let look = &part.look;
    let fields = [
        ("strata.format", FORMAT.to_string()),
        ("strata.version", p.strata_version.clone()),
        ("strata.device", p.device.clone()),
        ("strata.scene", p.scene.clone()),
        ("strata.settings", p.settings.clone()),
        ("strata.seed", p.seed.to_string()),
        ("strata.spp", sums.spp.to_string()),
        ("strata.samples", sums.samples.to_string()),
        // The exposure's bits, so that the merge resolves with exactly the value the render had.
        ("strata.exposure", format!("{:08x}", look.exposure.to_bits())),
        ("strata.tone_map", format!("{:?}", look.tone_map).to_ascii_lowercase()),
        ("strata.transparent", look.transparent.to_string()),
        ("strata.auto_exposure", look.auto_exposure.to_string()),
    ];
    for (key, value) in fields {
        let text = Text::new_or_none(value.as_str())
            .ok_or_else(|| anyhow!("{}: header field {key} is not plain ASCII: {value:?}", path.display()))?;
        attributes.other.insert(Text::from(key), AttributeValue::Text(text));
    }
    let size = Vec2(sums.width as usize, sums.height as usize);
    let layer = Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, channels);
    crate::output::write_atomic(path, |file| {
        Image::from_layer(layer)
            .write()
            .to_buffered(std::io::BufWriter::new(file))
            .map_err(|e| anyhow!("{e}"))
            .context("encoding the part's EXR")
    })
    .with_context(|| format!("writing the part {}", path.display()))
}

/// The most counts one sample adds to a channel (`shaders/include/fixed_point.glsl`).
pub const MAX_COUNTS_PER_SAMPLE: u64 = 1 << (SUM_MAX_SAMPLE_LOG2 + SUM_FRACTION_BITS);

/// Reads a part; a clear error naming the file when it is not one, is cut short, claims more than a render can
/// make, or is inconsistent. The header is checked before any pixel is read or any memory set aside for them.
pub fn read_part(path: &Path) -> Result<Part> {
    let (file, header) = crate::input::exr_header(path, MAX_IMAGE_SIDE as usize, "a part")?;
    read_checked_part(path, file, &header).with_context(|| format!("{}: not a readable strata part", path.display()))
}

fn read_checked_part(path: &Path, file: std::fs::File, header: &exr::meta::header::Header) -> Result<Part> {
    use exr::prelude::*;
    let mut expected: Vec<String> = SUM_CHANNELS
        .iter()
        .flat_map(|c| [format!("sum_hi.{c}"), format!("sum_lo.{c}")])
        .chain(["samples.Y".to_string()])
        .collect();
    expected.sort();
    let found: Vec<String> = header.channels.list.iter().map(|c| c.name.to_string()).collect();
    if found != expected || header.channels.list.iter().any(|c| c.sample_type != SampleType::U32) {
        bail!(
            "its channels are {}, a part's are the 32-bit integer channels {}",
            crate::input::excerpt(&found.join(", "), 200),
            expected.join(", ")
        );
    }
    let pixels = header.layer_size.0 as u64 * header.layer_size.1 as u64;
    // The decoded channels, then the 64-bit sums made of them.
    crate::input::ensure_memory(pixels * (4 * 9 + 8 * 4), path, "the part's pixels")?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::BufReader::new(file))
        .map_err(|e| anyhow!("{e}"))?;
    let layer = &image.layer_data;
    let field = |key: &str| -> anyhow::Result<String> {
        match layer.attributes.other.get(&Text::from(key)) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            Some(_) => bail!("header field {key} is not text"),
            None => bail!("the header has no {key} (written by strata render --samples, --shard or --checkpoint?)"),
        }
    };
    let format = field("strata.format")?;
    if format != FORMAT {
        bail!("part format {:?}, this strata reads {FORMAT:?}", crate::input::excerpt(&format, 40));
    }
    let number = |key: &str| -> anyhow::Result<u64> {
        let text = field(key)?;
        text.parse()
            .map_err(|_| anyhow!("header field {key} is {:?}, not a whole number", crate::input::excerpt(&text, 40)))
    };
    let boolean = |key: &str| -> anyhow::Result<bool> {
        let text = field(key)?;
        text.parse()
            .map_err(|_| anyhow!("header field {key} is {:?}, not true or false", crate::input::excerpt(&text, 40)))
    };
    let provenance = Provenance {
        strata_version: field("strata.version")?,
        device: field("strata.device")?,
        scene: field("strata.scene")?,
        settings: field("strata.settings")?,
        seed: number("strata.seed")?,
    };
    let exposure_bits = field("strata.exposure")?;
    let exposure = f32::from_bits(u32::from_str_radix(&exposure_bits, 16).map_err(|_| {
        anyhow!("header field strata.exposure is {:?}, not 8 hex digits", crate::input::excerpt(&exposure_bits, 40))
    })?);
    // As strictly as the render's own --exposure.
    if !(exposure.is_finite() && exposure.abs() <= MAX_EXPOSURE_STOPS) {
        bail!("header field strata.exposure is {exposure}, not a number of stops between -{MAX_EXPOSURE_STOPS} and {MAX_EXPOSURE_STOPS}");
    }
    let look = PartLook {
        exposure,
        tone_map: ToneMap::parse(&field("strata.tone_map")?)?,
        transparent: boolean("strata.transparent")?,
        auto_exposure: boolean("strata.auto_exposure")?,
    };
    let spp = number("strata.spp")?;
    if !(1..=u64::from(MAX_SPP)).contains(&spp) {
        bail!("header field strata.spp is {spp}; a frame has 1 to {MAX_SPP} samples");
    }
    let spp = spp as u32;
    let samples = SampleSet::parse(&field("strata.samples")?).context("header field strata.samples")?;
    if samples.is_empty() {
        bail!("it holds no samples (strata.samples is \"-\"): there is nothing to merge");
    }
    if samples.ranges().last().is_some_and(|&(_, end)| end > spp) {
        bail!("it holds samples {}, beyond the frame's {spp}", crate::input::excerpt(&samples.to_string(), 80));
    }
    let (width, height) = (layer.size.0 as u32, layer.size.1 as u32);
    let pixels = layer.size.0 * layer.size.1;
    let channel = |name: &str| -> anyhow::Result<&Vec<u32>> {
        let found = layer.channel_data.list.iter().find(|c| c.name == *name);
        match found.map(|c| &c.sample_data) {
            Some(FlatSamples::U32(values)) if values.len() == pixels => Ok(values),
            Some(_) => bail!("channel {name} is not {pixels} 32-bit integers"),
            None => bail!("it has no channel {name}"),
        }
    };
    if let Some(p) = channel("samples.Y")?.iter().position(|&n| n != samples.len()) {
        bail!("pixel {p} counts {} samples, the header {}", channel("samples.Y")?[p], samples.len());
    }
    // No render makes more than this: a larger sum is damage, not light.
    let most = u64::from(samples.len()) * MAX_COUNTS_PER_SAMPLE;
    let mut counts = vec![0u64; pixels * 4];
    for (c, name) in SUM_CHANNELS.iter().enumerate() {
        let hi = channel(&format!("sum_hi.{name}"))?;
        let lo = channel(&format!("sum_lo.{name}"))?;
        for p in 0..pixels {
            let count = (u64::from(hi[p]) << 32) | u64::from(lo[p]);
            if count > most {
                bail!(
                    "pixel ({}, {}) sums {count} counts in channel {name}, more than {} samples can make ({most})",
                    p % layer.size.0,
                    p / layer.size.0,
                    samples.len()
                );
            }
            counts[p * 4 + c] = count;
        }
    }
    Ok(Part { provenance, look, sums: PartialSums { width, height, spp, samples, counts } })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    pub(crate) use crate::scratch_dir as scratch;

    pub(crate) fn part(samples: (u32, u32), seed: u64) -> Part {
        let (width, height, spp) = (3, 2, 8);
        let counts = (0..width * height * 4).map(|i| (u64::from(i) << 40) + u64::from(samples.0) * 7 + 1).collect();
        Part {
            provenance: Provenance {
                strata_version: "0.1.0".into(),
                device: "test device".into(),
                scene: "fnv1a64:0".into(),
                settings: "fnv1a64:1".into(),
                seed,
            },
            look: PartLook { exposure: 0.3, tone_map: ToneMap::Filmic, transparent: false, auto_exposure: true },
            sums: PartialSums { width, height, spp, samples: SampleSet::range(samples.0, samples.1), counts },
        }
    }

    #[test]
    fn a_part_reads_back_as_written() {
        let path = scratch("round-trip").join("part.exr");
        let written = part((2, 6), 9);
        write_part(&path, &written).unwrap();
        assert_eq!(read_part(&path).unwrap(), written);
    }

    #[test]
    fn a_truncated_part_is_an_error_naming_the_file() {
        let path = scratch("truncated").join("part.exr");
        write_part(&path, &part((0, 8), 1)).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let err = format!("{:#}", read_part(&path).unwrap_err());
        assert!(err.contains("part.exr"), "{err}");
    }
}
