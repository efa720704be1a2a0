//! Importance sampling of an equirectangular environment (CPU twin of `shaders/include/environment.glsl`): a 2D
//! piecewise-constant distribution over its texels proportional to luminance × sin θ (the solid angle a texel
//! row covers), sampled as a marginal over rows then a conditional over the row's columns (Pharr, Jakob and
//! Humphreys, *Physically Based Rendering*, 4th ed., §A.5.3 and §12.5.2). A sample's density in (u, v) is
//! p(texel)·W·H; in solid angle, dω = 2π² sin θ du dv divides it by 2π² sin θ.
use glam::Vec2;
use std::f32::consts::PI;

#[derive(Debug, Clone, PartialEq)]
pub struct EnvironmentDistribution {
    pub width: u32,
    pub height: u32,
    /// Cumulative row probabilities: `height + 1` values from 0 to 1.
    pub marginal: Vec<f32>,
    /// Per row, cumulative column probabilities: `height × (width + 1)` values, each row from 0 to 1 (uniform
    /// where a row has no weight: it is never chosen then).
    pub conditional: Vec<f32>,
}

/// The largest index `i` in `0..n` with `cdf[i] <= u` (`cdf` has `n + 1` entries, non-decreasing), skipping
/// intervals of zero probability.
pub fn find_interval(cdf: &[f32], u: f32) -> usize {
    let n = cdf.len() - 1;
    let (mut lo, mut hi) = (0usize, n);
    // Invariant: cdf[lo] <= u (or lo = 0), and the answer is below hi.
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if cdf[mid] <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // u may sit exactly on a boundary followed by empty intervals: move to one with probability.
    while lo + 1 < n && cdf[lo + 1] - cdf[lo] <= 0.0 {
        lo += 1;
    }
    lo
}

impl EnvironmentDistribution {
    /// The distribution of a `width × height` image whose texels have luminance `luminance` (row-major, top row
    /// first). An image with no light at all gets a uniform distribution.
    pub fn new(width: u32, height: u32, luminance: &[f32]) -> Self {
        let (w, h) = (width as usize, height as usize);
        let mut conditional = Vec::with_capacity(h * (w + 1));
        let mut row_weights = Vec::with_capacity(h);
        for row in 0..h {
            let sin_theta = f64::from(((row as f32 + 0.5) / height as f32 * PI).sin());
            let weights: Vec<f64> =
                luminance[row * w..(row + 1) * w].iter().map(|&l| f64::from(l.max(0.0)) * sin_theta).collect();
            let sum: f64 = weights.iter().sum();
            row_weights.push(sum);
            conditional.push(0.0f32);
            let mut running = 0.0f64;
            for (i, weight) in weights.iter().enumerate() {
                running += if sum > 0.0 { weight / sum } else { 1.0 / w as f64 };
                conditional.push(if i + 1 == w { 1.0 } else { running as f32 });
            }
        }
        let total: f64 = row_weights.iter().sum();
        let mut marginal = Vec::with_capacity(h + 1);
        marginal.push(0.0f32);
        let mut running = 0.0f64;
        for (i, weight) in row_weights.iter().enumerate() {
            running += if total > 0.0 { weight / total } else { 1.0 / h as f64 };
            marginal.push(if i + 1 == h { 1.0 } else { running as f32 });
        }
        Self { width, height, marginal, conditional }
    }

    fn row_cdf(&self, row: usize) -> &[f32] {
        let n = self.width as usize + 1;
        &self.conditional[row * n..(row + 1) * n]
    }

    /// A point (u, v) of the image drawn from the distribution with uniform numbers `xi`, and its density in
    /// (u, v).
    pub fn sample(&self, xi: Vec2) -> (f32, f32, f32) {
        let row = find_interval(&self.marginal, xi.y);
        let p_row = self.marginal[row + 1] - self.marginal[row];
        let dv = if p_row > 0.0 { ((xi.y - self.marginal[row]) / p_row).clamp(0.0, 1.0) } else { 0.5 };
        let cdf = self.row_cdf(row);
        let column = find_interval(cdf, xi.x);
        let p_column = cdf[column + 1] - cdf[column];
        let du = if p_column > 0.0 { ((xi.x - cdf[column]) / p_column).clamp(0.0, 1.0) } else { 0.5 };
        let u = (column as f32 + du) / self.width as f32;
        let v = (row as f32 + dv) / self.height as f32;
        (u, v, p_row * p_column * self.width as f32 * self.height as f32)
    }

    /// The density in (u, v) of the point (u, v).
    pub fn pdf_uv(&self, u: f32, v: f32) -> f32 {
        let column = ((u * self.width as f32) as usize).min(self.width as usize - 1);
        let row = ((v * self.height as f32) as usize).min(self.height as usize - 1);
        let cdf = self.row_cdf(row);
        (self.marginal[row + 1] - self.marginal[row])
            * (cdf[column + 1] - cdf[column])
            * self.width as f32
            * self.height as f32
    }
}

/// A density in (u, v) as a density in solid angle at polar angle θ = π v.
pub fn solid_angle_pdf(pdf_uv: f32, v: f32) -> f32 {
    let sin_theta = (PI * v).sin();
    if sin_theta <= 0.0 {
        0.0
    } else {
        pdf_uv / (2.0 * PI * PI * sin_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_lands_in_the_one_bright_texel_with_its_density() {
        let mut lum = vec![0.0; 8 * 4];
        lum[2 * 8 + 5] = 3.0;
        let d = EnvironmentDistribution::new(8, 4, &lum);
        for xi in [Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.99), Vec2::new(0.0, 0.0)] {
            let (u, v, pdf) = d.sample(xi);
            assert_eq!(((u * 8.0) as u32, (v * 4.0) as u32), (5, 2), "{xi}");
            assert!((pdf - 32.0).abs() < 1e-4, "all the mass in 1/32 of the square: {pdf}");
            assert_eq!(d.pdf_uv(u, v), pdf);
        }
        assert_eq!(d.pdf_uv(0.1, 0.1), 0.0);
    }

    #[test]
    fn the_density_integrates_to_one_over_the_sphere() {
        let lum: Vec<f32> = (0..16 * 8).map(|i| 0.1 + (i % 7) as f32).collect();
        let d = EnvironmentDistribution::new(16, 8, &lum);
        // ∫ p_ω dω = ∫∫ p_ω · 2π² sin θ du dv, by the midpoint rule on a fine grid.
        let n = 512;
        let mut sum = 0.0f64;
        for j in 0..n {
            for i in 0..n {
                let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let p = solid_angle_pdf(d.pdf_uv(u, v), v);
                sum += f64::from(p * 2.0 * PI * PI * (PI * v).sin()) / (n * n) as f64;
            }
        }
        assert!((sum - 1.0).abs() < 1e-3, "{sum}");
    }

    #[test]
    fn empty_rows_are_never_chosen_and_a_black_image_is_uniform() {
        let mut lum = vec![0.0; 4 * 4];
        lum[4 * 3] = 1.0;
        let d = EnvironmentDistribution::new(4, 4, &lum);
        for k in 0..64 {
            let (_, v, _) = d.sample(Vec2::new(0.5, k as f32 / 64.0));
            assert_eq!((v * 4.0) as u32, 3);
        }
        let black = EnvironmentDistribution::new(4, 4, &[0.0; 16]);
        assert!((black.pdf_uv(0.3, 0.3) - 1.0).abs() < 1e-6);
    }
}
