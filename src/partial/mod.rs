//! Parts of a frame: the fixed-point sums of some of its samples (`shaders/include/fixed_point.glsl`), the
//! file that carries them between machines, and the splits that make them. Integer sums add exactly in any
//! order, so parts rendered anywhere (`--samples A..B`, `--shard K/N`, a checkpoint) merge to the bits one
//! uninterrupted render makes.
pub mod file;
pub mod merge;
pub mod sample_set;
pub mod shard;

pub use sample_set::SampleSet;

use anyhow::{bail, Result};

/// Bytes per pixel of the sums: four channels of 64 bits.
pub const BYTES_PER_PIXEL: u64 = 32;

/// Per pixel, four 64-bit counts of 2^-SUM_FRACTION_BITS (RGBA, row-major, top row first) summing the
/// samples `samples` of a frame of `spp`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PartialSums {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub samples: SampleSet,
    pub counts: Vec<u64>,
}

impl PartialSums {
    /// Nothing summed yet.
    pub fn zero(width: u32, height: u32, spp: u32) -> Self {
        let counts = vec![0; width as usize * height as usize * 4];
        Self { width, height, spp, samples: SampleSet::default(), counts }
    }

    /// An error unless these sums belong to a frame of this size and sample count.
    pub fn check_fits(&self, width: u32, height: u32, spp: u32) -> Result<()> {
        if (self.width, self.height, self.spp) != (width, height, spp) {
            bail!(
                "the sums are of a {}x{} frame of {} samples, not {width}x{height} of {spp}",
                self.width,
                self.height,
                self.spp
            );
        }
        if self.counts.len() != width as usize * height as usize * 4 {
            bail!("the sums hold {} values, a {width}x{height} frame needs {}", self.counts.len(), width * height * 4);
        }
        Ok(())
    }

    /// Adds another part's sums: exact integer addition, so the order of parts does not matter. An error when
    /// the parts share a sample or belong to different frames.
    pub fn add(&mut self, other: &PartialSums) -> Result<()> {
        other.check_fits(self.width, self.height, self.spp)?;
        self.samples = self.samples.union(&other.samples)?;
        for (sum, add) in self.counts.iter_mut().zip(&other.counts) {
            // 2^47 counts per sample at most (fixed_point.glsl), 65536 samples: no sum can overflow.
            *sum = sum.checked_add(*add).ok_or_else(|| anyhow::anyhow!("a sum overflowed 64 bits"))?;
        }
        Ok(())
    }
}
