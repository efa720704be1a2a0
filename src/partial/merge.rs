//! Merging parts on the host: they must come from one render (the same provenance and look) and hold every
//! sample of the frame exactly once; the sums then add exactly (integers), in whatever order the parts come.
use super::file::{read_part, Part};
use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// Reads and adds the parts at `paths`. With `complete`, they must hold every sample of the frame; without,
/// any samples at most once (a merge of some parts into a bigger part).
pub fn merge_parts(paths: &[PathBuf], complete: bool) -> Result<Part> {
    let Some(first_path) = paths.first() else { bail!("no parts to merge") };
    let mut merged = read_part(first_path)?;
    // Which file holds which samples, to name both files of an overlap.
    let mut holders: Vec<(&Path, super::SampleSet)> = vec![(first_path, merged.sums.samples.clone())];
    for path in &paths[1..] {
        let part = read_part(path)?;
        if let Some((field, theirs, ours)) = merged.provenance.difference(&part.provenance) {
            bail!(
                "{}: a part of another render: its {field} is {ours}, {}'s is {theirs}",
                path.display(),
                first_path.display()
            );
        }
        if part.look != merged.look {
            bail!("{}: resolved with other display settings than {}", path.display(), first_path.display());
        }
        let (s, p) = (&merged.sums, &part.sums);
        if (s.width, s.height, s.spp) != (p.width, p.height, p.spp) {
            bail!(
                "{}: a {}x{} frame of {} samples, {} is {}x{} of {}",
                path.display(),
                p.width,
                p.height,
                p.spp,
                first_path.display(),
                s.width,
                s.height,
                s.spp
            );
        }
        for (holder, held) in &holders {
            if let Some((a, b)) = held.overlap(&p.samples) {
                bail!(
                    "{} and {} both hold samples {a}..{b}: each sample must be in one part",
                    holder.display(),
                    path.display()
                );
            }
        }
        holders.push((path, p.samples.clone()));
        merged.sums.add(p)?;
    }
    let gaps = merged.sums.samples.gaps(merged.sums.spp);
    if complete && !gaps.is_empty() {
        let named: Vec<String> = gaps.iter().map(|(a, b)| format!("{a}..{b}")).collect();
        bail!(
            "the parts hold samples {} of the frame's {}: samples {} are in no part (missing a shard?)",
            merged.sums.samples,
            merged.sums.spp,
            named.join(", ")
        );
    }
    Ok(merged)
}

#[cfg(test)]
mod tests {
    use super::super::file::{tests::part, tests::scratch, write_part};
    use super::*;

    fn written(dir: &Path, parts: &[Part]) -> Vec<PathBuf> {
        parts
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let path = dir.join(format!("part{i}.exr"));
                write_part(&path, p).unwrap();
                path
            })
            .collect()
    }

    #[test]
    fn parts_in_any_order_add_to_the_same_sums() {
        let dir = scratch("merge-order");
        let parts = [part((0, 3), 5), part((3, 4), 5), part((4, 8), 5)];
        let paths = written(&dir, &parts);
        let forward = merge_parts(&paths, true).unwrap();
        let backward = merge_parts(&paths.iter().rev().cloned().collect::<Vec<_>>(), true).unwrap();
        assert_eq!(forward, backward);
        assert_eq!(forward.sums.samples.len(), 8);
        let expected: Vec<u64> =
            (0..parts[0].sums.counts.len()).map(|i| parts.iter().map(|p| p.sums.counts[i]).sum()).collect();
        assert_eq!(forward.sums.counts, expected);
    }

    #[test]
    fn a_gap_an_overlap_and_another_seed_are_errors_naming_them() {
        let dir = scratch("merge-errors");
        let gap = written(&dir, &[part((0, 3), 5), part((5, 8), 5)]);
        let err = format!("{:#}", merge_parts(&gap, true).unwrap_err());
        assert!(err.contains("samples 3..5 are in no part"), "{err}");
        assert!(merge_parts(&gap, false).is_ok(), "an incomplete merge may leave gaps");

        let dir = scratch("merge-overlap");
        let overlap = written(&dir, &[part((0, 5), 5), part((4, 8), 5)]);
        let err = format!("{:#}", merge_parts(&overlap, true).unwrap_err());
        assert!(err.contains("part0.exr and") && err.contains("part1.exr both hold samples 4..5"), "{err}");

        let dir = scratch("merge-seed");
        let seeds = written(&dir, &[part((0, 4), 5), part((4, 8), 6)]);
        let err = format!("{:#}", merge_parts(&seeds, true).unwrap_err());
        assert!(err.contains("part1.exr") && err.contains("seed"), "{err}");
    }
}
