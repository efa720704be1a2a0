//! Which samples of a frame a part holds: sorted, disjoint, half-open ranges.
use anyhow::{anyhow, bail, Result};
use std::fmt;

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SampleSet {
    /// Sorted, disjoint, never touching (adjacent ranges are joined), none empty.
    ranges: Vec<(u32, u32)>,
}

impl SampleSet {
    /// The samples `start..end` (empty when `end <= start`).
    pub fn range(start: u32, end: u32) -> Self {
        Self { ranges: if start < end { vec![(start, end)] } else { Vec::new() } }
    }

    pub fn ranges(&self) -> &[(u32, u32)] {
        &self.ranges
    }

    /// How many samples.
    pub fn len(&self) -> u32 {
        self.ranges.iter().map(|(a, b)| b - a).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// The first sample both sets hold, as the overlapping range. Linear: both lists are sorted.
    pub fn overlap(&self, other: &SampleSet) -> Option<(u32, u32)> {
        let (mut i, mut j) = (0, 0);
        while i < self.ranges.len() && j < other.ranges.len() {
            let ((a0, a1), (b0, b1)) = (self.ranges[i], other.ranges[j]);
            let (start, end) = (a0.max(b0), a1.min(b1));
            if start < end {
                return Some((start, end));
            }
            if a1 <= b1 {
                i += 1;
            } else {
                j += 1;
            }
        }
        None
    }

    /// Both sets together; an error naming the samples they share.
    pub fn union(&self, other: &SampleSet) -> Result<SampleSet> {
        if let Some((a, b)) = self.overlap(other) {
            bail!("samples {a}..{b} are in both");
        }
        Self::joined(self.ranges.iter().chain(&other.ranges).copied().collect())
    }

    /// Ranges in any order as a set: sorted, checked for overlaps, neighbours joined. O(n log n).
    fn joined(mut all: Vec<(u32, u32)>) -> Result<SampleSet> {
        all.sort_unstable();
        let mut ranges: Vec<(u32, u32)> = Vec::with_capacity(all.len());
        for (start, end) in all {
            match ranges.last_mut() {
                Some(last) if start < last.1 => bail!("samples {start}..{} are given twice", end.min(last.1)),
                Some(last) if last.1 == start => last.1 = end,
                _ => ranges.push((start, end)),
            }
        }
        Ok(SampleSet { ranges })
    }

    /// The samples of `0..spp` this set lacks.
    pub fn gaps(&self, spp: u32) -> Vec<(u32, u32)> {
        let mut gaps = Vec::new();
        let mut next = 0;
        for &(start, end) in &self.ranges {
            if start > next {
                gaps.push((next, start.min(spp)));
            }
            next = end;
        }
        if next < spp {
            gaps.push((next, spp));
        }
        gaps.retain(|(a, b)| a < b);
        gaps
    }

    /// The samples of `want` this set lacks, which must be one range (a checkpoint holds a prefix of its
    /// part); None when it lacks nothing.
    pub fn remaining_of(&self, want: (u32, u32)) -> Result<Option<(u32, u32)>> {
        if let Some(&(a, b)) = self.ranges.iter().find(|&&(a, b)| a < want.0 || b > want.1) {
            bail!("it holds samples {a}..{b}, outside the {}..{} this render makes", want.0, want.1);
        }
        let missing = SampleSet::range(want.0, want.1).minus(self);
        match missing.as_slice() {
            [] => Ok(None),
            [one] => Ok(Some(*one)),
            _ => bail!("the samples it lacks ({}) are not one range", SampleSet { ranges: missing }),
        }
    }

    /// The ranges of this set that `other` does not hold.
    fn minus(&self, other: &SampleSet) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for &(mut start, end) in &self.ranges {
            for &(o0, o1) in &other.ranges {
                if o1 <= start || o0 >= end {
                    continue;
                }
                if o0 > start {
                    out.push((start, o0));
                }
                start = start.max(o1);
            }
            if start < end {
                out.push((start, end));
            }
        }
        out
    }

    /// Reads what [`fmt::Display`] writes: `0..16,32..48` (or `-` for none). Errors quote only the range at fault.
    pub fn parse(text: &str) -> Result<SampleSet> {
        if text.trim() == "-" {
            return Ok(SampleSet::default());
        }
        let ranges = text.split(',').map(parse_range).collect::<Result<Vec<_>>>()?;
        Self::joined(ranges)
    }
}

impl fmt::Display for SampleSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.ranges.is_empty() {
            return f.write_str("-");
        }
        let parts: Vec<String> = self.ranges.iter().map(|(a, b)| format!("{a}..{b}")).collect();
        f.write_str(&parts.join(","))
    }
}

/// `A..B` with A < B.
pub fn parse_range(text: &str) -> Result<(u32, u32)> {
    let shown = crate::input::excerpt(text, 40);
    let (a, b) = text.trim().split_once("..").ok_or_else(|| anyhow!("{shown:?}: expected A..B, e.g. 0..16"))?;
    let number = |s: &str| {
        s.trim()
            .parse::<u32>()
            .map_err(|_| anyhow!("{shown:?}: {:?} is not a whole number", crate::input::excerpt(s, 20)))
    };
    let (a, b) = (number(a)?, number(b)?);
    if a >= b {
        bail!("{shown:?}: the range is empty (A..B takes the samples A to B-1)");
    }
    Ok((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_joins_neighbours_and_refuses_overlaps() {
        let a = SampleSet::range(0, 8).union(&SampleSet::range(16, 24)).unwrap();
        let b = a.union(&SampleSet::range(8, 16)).unwrap();
        assert_eq!(b.ranges(), &[(0, 24)]);
        assert_eq!(b.len(), 24);
        let err = a.union(&SampleSet::range(4, 12)).unwrap_err().to_string();
        assert!(err.contains("4..8"), "{err}");
    }

    #[test]
    fn gaps_name_what_is_missing() {
        let s = SampleSet::range(4, 8).union(&SampleSet::range(10, 12)).unwrap();
        assert_eq!(s.gaps(16), vec![(0, 4), (8, 10), (12, 16)]);
        assert!(SampleSet::range(0, 16).gaps(16).is_empty());
    }

    #[test]
    fn text_round_trips() {
        let s = SampleSet::parse("32..48,0..16").unwrap();
        assert_eq!(s.to_string(), "0..16,32..48");
        assert_eq!(SampleSet::parse(&SampleSet::default().to_string()).unwrap(), SampleSet::default());
        assert!(SampleSet::parse("5..5").is_err());
        assert!(SampleSet::parse("0..8,4..9").is_err());
    }

    #[test]
    fn a_hundred_thousand_ranges_parse_and_compare_in_linear_time() {
        let many: Vec<String> = (0..100_000u32).rev().map(|i| format!("{}..{}", 2 * i, 2 * i + 1)).collect();
        let started = std::time::Instant::now();
        let set = SampleSet::parse(&many.join(",")).unwrap();
        let other = SampleSet::parse(
            &(0..100_000u32).map(|i| format!("{}..{}", 2 * i + 1, 2 * i + 2)).collect::<Vec<_>>().join(","),
        )
        .unwrap();
        assert_eq!(set.ranges().len(), 100_000);
        assert_eq!(set.overlap(&other), None);
        assert_eq!(set.union(&other).unwrap().ranges(), &[(0, 200_000)]);
        // Quadratic work here took 12 s; linear takes milliseconds. The bound is loose: it only tells the two apart.
        assert!(started.elapsed().as_secs_f64() < 3.0, "{:?}", started.elapsed());
        let err = SampleSet::parse(&format!("{},7..9", many.join(","))).unwrap_err().to_string();
        assert!(err.contains("given twice") && err.len() < 200, "{err}");
    }

    #[test]
    fn what_a_checkpoint_lacks_is_its_range_minus_what_it_holds() {
        let held = SampleSet::range(8, 20);
        assert_eq!(held.remaining_of((8, 32)).unwrap(), Some((20, 32)));
        assert_eq!(held.remaining_of((8, 20)).unwrap(), None);
        assert_eq!(SampleSet::default().remaining_of((0, 4)).unwrap(), Some((0, 4)));
        assert!(held.remaining_of((10, 32)).is_err(), "holds samples outside the range");
        assert!(SampleSet::range(12, 16).remaining_of((8, 32)).is_err(), "two holes");
    }
}
