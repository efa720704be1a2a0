//! Measurements on rendered frames that the optics cases (and the tests) make: profiles across an edge, where
//! they cross a level, how wide they rise.
use crate::output::Frame;

/// Mean red radiance over the whole frame.
pub fn mean_red(frame: &Frame) -> f32 {
    frame.pixels.iter().map(|p| p[0]).sum::<f32>() / frame.pixels.len() as f32
}

/// Mean red radiance of each column over rows `rows`.
pub fn column_profile(frame: &Frame, rows: std::ops::Range<u32>) -> Vec<f32> {
    (0..frame.width).map(|x| rows.clone().map(|y| frame.pixel(x, y)[0]).sum::<f32>() / rows.len() as f32).collect()
}

/// Mean red radiance of each row over columns `columns`.
pub fn row_profile(frame: &Frame, columns: std::ops::Range<u32>) -> Vec<f32> {
    (0..frame.height)
        .map(|y| columns.clone().map(|x| frame.pixel(x, y)[0]).sum::<f32>() / columns.len() as f32)
        .collect()
}

/// Where a rising profile first crosses `level` (linear interpolation between pixel centres, in pixels from the
/// left edge of pixel 0).
pub fn crossing(profile: &[f32], level: f32) -> Option<f32> {
    profile
        .windows(2)
        .enumerate()
        .find_map(|(i, w)| (w[0] < level && w[1] >= level).then(|| i as f32 + 0.5 + (level - w[0]) / (w[1] - w[0])))
}

/// The 10%–90% rise width of a profile that goes from `low` to `high`, in pixels; None when it does not cross
/// both levels.
pub fn rise_width(profile: &[f32], low: f32, high: f32) -> Option<f32> {
    let a = crossing(profile, low + 0.1 * (high - low))?;
    let b = crossing(profile, low + 0.9 * (high - low))?;
    Some(b - a)
}

/// Pixels with a NaN or infinite channel.
pub fn non_finite_pixels(frame: &Frame) -> usize {
    frame.pixels.iter().filter(|p| p.iter().any(|v| !v.is_finite())).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_linear_ramp_rises_over_four_fifths_of_its_length() {
        // 0 up to pixel 10, then +0.1 per pixel to 1 at pixel 20.
        let profile: Vec<f32> = (0..30).map(|i| ((i as f32 - 10.0) / 10.0).clamp(0.0, 1.0)).collect();
        let width = rise_width(&profile, 0.0, 1.0).unwrap();
        assert!((width - 8.0).abs() < 1e-4, "{width}");
        assert!((crossing(&profile, 0.5).unwrap() - 15.5).abs() < 1e-4);
        assert_eq!(rise_width(&[0.0, 0.05, 0.0], 0.0, 1.0), None);
    }
}
