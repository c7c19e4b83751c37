//! How the camera samples beyond the placed ones are taken, chosen from the placed
//! samples' own statistics: a coarser march (step K·Δ) and fewer samples of the
//! straight light per march point make a camera sample cheaper and noisier; which
//! pays depends on the scene (a staircase's god rays, a lamp's halo, open fog), so
//! it is measured per render rather than fixed (efficiency-aware splitting, as in
//! Rath et al. 2022: minimise variance × cost).
//!
//! Both costs are measured for free on the placed samples, which march at Δ with
//! the view's n straight-light samples:
//! - the coarse march with offset (j + ξ)/K visits exactly the fine march's points
//!   n ≡ j (mod K), weighted K·Δ; its estimators' mean over j is the fine one, so
//!   (law of total variance) the coarse march adds their spread around it;
//! - n/4 or n/2 straight-light samples: the added variance of an aligned block of
//!   the point's set ([`DirectSpread`]), K·Σ (T w Δ)² of it along the ray.
//!
//! Cost is counted in rays (deterministic, unlike seconds) plus [`POINT_COST`] per
//! march point; every statistic is summed per pixel in sample order, then over the
//! pixels in order, so the choice does not depend on the thread count.
//!
//! The march share is predicted too, and taken when a user asks: a share given
//! (`CachedRenderParams::image_march_every`) or one chosen by [`share_cost`]
//! (`CachedRenderParams::adapt_march_share`; see [`choose`]): only one
//! in m of the later camera samples marches (in runs, [`MARCH_RUN`]; the first
//! surface is sampled by all of them, the medium part averaged over the marched
//! ones). Where the march is most of a sample's cost and the first surface's
//! light most of the pixel's variance (sunlit patches, emitters' edges), the
//! image gains many surface samples for a few of the medium's. With N samples,
//! N/m marched, N·Var = (V − V_m) + m·V_m (V the total's variance, V_m the medium
//! part's: the surface's variance and its covariance with the medium are what the
//! total has beyond the medium's).

use crate::core::color::Rgb;
use crate::core::color::luminance;
use crate::pipeline::path::DirectSpread;
use serde::{Deserialize, Serialize};

/// The march factors K tried (step K·Δ).
pub const MARCH_FACTORS: [u32; 4] = [1, 2, 4, 8];

/// A march point's own cost in rays beyond the rays it traces (the records'
/// lookup and weights, transmittance, the sampler), set to one ray: at budget 1
/// the adaptive reconstructions it made equal in cost took 0.97–1.23× the fixed
/// march's seconds (fog_box, lamp_fog, the panel scene, the staircase; seeds 1–2,
/// on a machine shared with other work; one outlier 1.43).
pub const POINT_COST: f64 = 1.0;

/// The march shares predicted: one in m of the later camera samples marches
/// ([`marches`]).
pub const MARCH_EVERY: [u32; 5] = [1, 2, 4, 8, 16];

/// At most this many times the fine samples' count is taken at equal cost (a
/// sample the statistics call nearly free must not multiply the image's time).
pub const MAX_SAMPLE_GAIN: f64 = 16.0;

/// What the camera samples beyond the placed ones take, and what the placed
/// samples predicted for it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageSplit {
    /// March step K·Δ.
    pub march_factor: u32,
    /// Straight-light samples per march point (None: the records hold that light).
    pub direct_samples: Option<u32>,
    /// One camera sample in this many marches (the others see the first surface
    /// only).
    #[serde(default = "one")]
    pub march_every: u32,
    /// Predicted variance of a camera sample, relative to the fine march's: of the
    /// image, and of its medium part.
    pub variance_ratio: f64,
    pub medium_variance_ratio: f64,
    /// Predicted cost of a camera sample, relative to the fine march's.
    pub cost_ratio: f64,
}

fn one() -> u32 {
    1
}

impl ImageSplit {
    /// The fine march with `direct` samples: what the placed samples take.
    pub fn fine(direct: Option<u32>) -> Self {
        ImageSplit {
            march_factor: 1,
            direct_samples: direct,
            march_every: 1,
            variance_ratio: 1.0,
            medium_variance_ratio: 1.0,
            cost_ratio: 1.0,
        }
    }
}

/// One camera sample's march, as it is walked: the coarse estimators' sums.
#[derive(Clone, Copy, Debug, Default)]
pub struct MarchSpread {
    /// Σ luminance of each point's contribution T w Δ L_s (the fine estimate).
    fine: f64,
    /// Per K = 2, 4, 8 (slots 0..2, 2..6, 6..14): K × Σ over points n ≡ j (mod K).
    coarse: [f64; 14],
    /// Σ (T w Δ)² × added variance of n/4 and n/2 straight-light samples.
    direct_added: [f64; 2],
    point_rays: f64,
    direct_rays: f64,
}

impl MarchSpread {
    /// Point `n` contributed `c` (T w Δ L_s) with straight-light spread `direct`
    /// (scaled by (T w Δ)² = `scale²`), tracing `rays` of which `direct_rays` for
    /// the straight light.
    pub fn add(
        &mut self,
        n: usize,
        c: Rgb,
        (scale, direct): (f64, Option<DirectSpread>),
        (rays, direct_rays): (u64, u64),
    ) {
        let y = luminance(c);
        self.fine += y;
        let mut slot = 0;
        for k in [2usize, 4, 8] {
            self.coarse[slot + n % k] += k as f64 * y;
            slot += k;
        }
        if let Some(d) = direct {
            for (acc, a) in self.direct_added.iter_mut().zip(d.added) {
                *acc += a.map_or(0.0, |(_, v)| scale * scale * v);
            }
        }
        self.point_rays += (rays - direct_rays) as f64 + POINT_COST;
        self.direct_rays += direct_rays as f64;
    }
}

/// A pixel's statistics over its placed camera samples.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelSpread {
    samples: u32,
    /// Σ and Σ² of the samples' total luminance, and of their medium part's.
    y: (f64, f64),
    y_medium: (f64, f64),
    /// Σ over samples of the coarse march's added variance, K = 2, 4, 8.
    march_added: [f64; 3],
    direct_added: [f64; 2],
    /// Σ over samples of the rays before the march, along it (lookups, path
    /// traced points) and of the straight light.
    fixed_rays: f64,
    point_rays: f64,
    direct_rays: f64,
}

impl PixelSpread {
    /// One camera sample: its total and medium part, the rays it traced before
    /// marching, its march.
    pub fn add(&mut self, (total, medium): (Rgb, Rgb), fixed_rays: u64, m: &MarchSpread) {
        let (y, ym) = (luminance(total), luminance(medium));
        self.samples += 1;
        self.y = (self.y.0 + y, self.y.1 + y * y);
        self.y_medium = (self.y_medium.0 + ym, self.y_medium.1 + ym * ym);
        let mut slot = 0;
        for (i, k) in [2usize, 4, 8].into_iter().enumerate() {
            let spread: f64 = m.coarse[slot..slot + k].iter().map(|e| (e - m.fine).powi(2)).sum();
            self.march_added[i] += spread / k as f64;
            slot += k;
        }
        for i in 0..2 {
            self.direct_added[i] += m.direct_added[i];
        }
        self.fixed_rays += fixed_rays as f64;
        self.point_rays += m.point_rays;
        self.direct_rays += m.direct_rays;
    }
}

/// The (K, straight-light samples) of least variance × cost over the window's
/// pixels, their placed samples marched at Δ with `direct` straight-light samples
/// (candidates n/4, n/2, n where n divides), every camera sample marching — and,
/// with `share`, then the march share of that (K, n) by [`share_cost`].
/// Returns it and every candidate ([`candidates`], the march shares' included).
///
/// The variance weighed for (K, n) is the worse of the image's and the medium
/// part's ratios: what a march adds is all the medium's, so the medium never pays
/// for the image's gain. A march share (`CachedRenderParams::image_march_every`)
/// trades the medium's variance for the first surface's instead, so it is chosen
/// only where a user asks (`--image-march-every auto`, by [`share_cost`]). Chosen
/// by default (then weighed by √(image ratio × medium ratio) × cost), at the
/// budget test's panel scene (12×9) it took one sample in two: against a
/// 65,536-spp reference of the same seed, at budget 1 the image's RMSE fell
/// 17–38% (medium −9…+21%; seeds 6–9, equal rays), at budget 4 it moved
/// −11…+27%, the image's error there being two pixels on the lamp's edge, so the
/// error no longer fell with the budget (README).
pub fn choose(pixels: &[PixelSpread], direct: Option<u32>, share: bool) -> (ImageSplit, Vec<ImageSplit>) {
    let all = candidates(pixels, direct);
    let product = |s: &ImageSplit| s.variance_ratio.max(s.medium_variance_ratio) * s.cost_ratio;
    let unshared = all.iter().copied().filter(|c| c.march_every == 1);
    let best = least(unshared, ImageSplit::fine(direct), product);
    if !share {
        return (best, all);
    }
    let same_march = |c: &&ImageSplit| (c.march_factor, c.direct_samples) == (best.march_factor, best.direct_samples);
    (least(all.iter().filter(same_march).copied(), best, share_cost), all)
}

/// The first of `start` and `of` with the least `rule` (ties keep the earlier).
fn least(of: impl Iterator<Item = ImageSplit>, start: ImageSplit, rule: impl Fn(&ImageSplit) -> f64) -> ImageSplit {
    of.fold(start, |best, c| if rule(&c) < rule(&best) { c } else { best })
}

/// What a march share is chosen by: the image's and the medium part's variance
/// ratios, summed, times the cost ratio — the sum of the two parts' mean squared
/// errors at equal time, each relative to the fine march's, so that each part
/// weighs alike whatever its size. Every share the sum lowers lowers at least one
/// part's equal-time error; the medium's may rise (m·V_m grows with m) where the
/// image gains more.
pub fn share_cost(s: &ImageSplit) -> f64 {
    (s.variance_ratio + s.medium_variance_ratio) * s.cost_ratio
}

/// Every (K, straight-light samples, march share) with its predicted variance and
/// cost ratios, the fine march first (none when the statistics are not finite).
/// Sums run over the pixels in order.
pub fn candidates(pixels: &[PixelSpread], direct: Option<u32>) -> Vec<ImageSplit> {
    let mut total = PixelSpread::default();
    // The pixels' own sample variances, of the total and of the medium part: what
    // every choice starts from (none is known with one sample: then only the
    // added variance is weighed, which favours the fine march).
    let (mut base, mut base_medium) = (0.0, 0.0);
    let variance = |(s, s2): (f64, f64), n: f64| ((s2 - s * s / n) / (n - 1.0)).max(0.0);
    for p in pixels.iter().filter(|p| p.samples > 0) {
        let n = p.samples as f64;
        if ![p.y.0, p.y.1, p.y_medium.0, p.y_medium.1].iter().all(|v| v.is_finite()) {
            return Vec::new();
        }
        if p.samples > 1 {
            base += variance(p.y, n);
            base_medium += variance(p.y_medium, n);
        }
        for i in 0..3 {
            total.march_added[i] += p.march_added[i] / n;
        }
        for i in 0..2 {
            total.direct_added[i] += p.direct_added[i] / n;
        }
        total.fixed_rays += p.fixed_rays / n;
        total.point_rays += p.point_rays / n;
        total.direct_rays += p.direct_rays / n;
    }
    let fine_cost = total.fixed_rays + total.point_rays + total.direct_rays;
    if !(fine_cost > 0.0
        && total
            .march_added
            .iter()
            .chain(&total.direct_added)
            .all(|a| a.is_finite()))
    {
        return Vec::new();
    }
    // Candidates for the straight light: (samples, fraction of n, added variance).
    let mut lights = vec![(direct, 1.0, 0.0)];
    if let Some(n) = direct {
        if n % 4 == 0 {
            lights.push((Some(n / 4), 0.25, total.direct_added[0]));
        }
        if n % 2 == 0 {
            lights.push((Some(n / 2), 0.5, total.direct_added[1]));
        }
    }
    // (A zero variance stays so only if nothing is added: a black image takes the
    // cheapest split that adds nothing.)
    let ratio = |v: f64, fine: f64| match (v > 0.0, fine > 0.0) {
        (_, true) => v / fine,
        (true, false) => f64::INFINITY,
        (false, false) => 1.0,
    };
    let mut all = Vec::new();
    for m in MARCH_EVERY {
        let mf = m as f64;
        for (i, &k) in MARCH_FACTORS.iter().enumerate() {
            let march_added = if i == 0 { 0.0 } else { total.march_added[i - 1] };
            for &(samples, share, direct_added) in &lights {
                // Per camera sample, the medium's variance is counted m times over.
                let medium = base_medium + march_added + k as f64 * direct_added;
                let march_cost = (total.point_rays + share * total.direct_rays) / k as f64;
                all.push(ImageSplit {
                    march_factor: k,
                    direct_samples: samples,
                    march_every: m,
                    variance_ratio: ratio(base + medium - base_medium + (mf - 1.0) * medium, base),
                    medium_variance_ratio: ratio(mf * medium, base_medium),
                    cost_ratio: (total.fixed_rays + march_cost / mf) / fine_cost,
                });
            }
        }
    }
    all
}

/// The marched camera samples beyond the placed ones come in runs of this many
/// consecutive ones, one run in every `march_every`: a pixel's camera samples are
/// a scrambled Sobol' set, whose aligned runs of 2^j points stratify the pixel
/// (a (0, j, 2)-net), while a stride (every m-th sample) would hold the marched
/// ones to one m-th of it — unbiased only over many renders, and with a
/// standard error that would not see it.
pub const MARCH_RUN: u32 = 8;

/// Whether camera sample `k` of a pixel marches: the `first` all do, then those
/// of the runs ([`MARCH_RUN`]) that begin every `split.march_every` runs.
pub fn marches(k: u32, first: u32, split: &ImageSplit) -> bool {
    let period = split.march_every.max(1).saturating_mul(MARCH_RUN);
    k < first || k % period < MARCH_RUN
}

/// Camera samples marched among the first `done` of a pixel ([`marches`]).
pub fn marched_samples(done: u32, first: u32, split: &ImageSplit) -> u32 {
    let period = split.march_every.max(1).saturating_mul(MARCH_RUN);
    // Samples below n in a run: whole periods, then the start of the last.
    let in_runs = |n: u32| n / period * MARCH_RUN + (n % period).min(MARCH_RUN);
    if done <= first {
        done
    } else {
        first + in_runs(done) - in_runs(first)
    }
}

/// The cost of a camera sample when one in `m` marches, relative to every one
/// marching, from the rays of samples that all marched: `total` of which `fixed`
/// before the march (as [`candidates`]' cost ratio, without the march points' own
/// cost, which only marching samples have). 1 without rays.
pub fn shared_cost_ratio(fixed: u64, total: u64, m: u32) -> f64 {
    if total == 0 {
        return 1.0;
    }
    let fixed = fixed.min(total) as f64;
    (fixed + (total as f64 - fixed) / m.max(1) as f64) / total as f64
}

/// Camera samples of `split` costing what `fine` fine samples cost (at least one
/// each, at most [`MAX_SAMPLE_GAIN`] times as many).
pub fn equal_cost_samples(fine: u32, split: &ImageSplit) -> u32 {
    let gain = (1.0 / split.cost_ratio).clamp(1.0, MAX_SAMPLE_GAIN);
    ((fine as f64 * gain).round() as u32).max(fine)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pixel(samples: u32, var: f64, march: [f64; 3], direct: [f64; 2], rays: (f64, f64, f64)) -> PixelSpread {
        let n = samples as f64;
        PixelSpread {
            samples,
            // Σy = 0 and Σy² = (n−1)·var give a sample variance of var.
            y: (0.0, (n - 1.0) * var),
            y_medium: (0.0, (n - 1.0) * var / 2.0),
            march_added: march.map(|a| a * n),
            direct_added: direct.map(|a| a * n),
            fixed_rays: rays.0 * n,
            point_rays: rays.1 * n,
            direct_rays: rays.2 * n,
        }
    }

    /// A march whose coarse estimators agree with the fine one (smooth light along
    /// the ray) and whose straight light is nearly noise-free is taken at K = 8
    /// with n/4 samples; one whose coarse estimators spread far stays fine.
    #[test]
    fn the_choice_weighs_added_variance_against_cost() {
        let smooth = vec![pixel(8, 1.0, [0.01, 0.02, 0.04], [0.001, 0.0005], (10.0, 40.0, 160.0)); 4];
        let s = choose(&smooth, Some(4), false).0;
        assert_eq!((s.march_factor, s.direct_samples), (8, Some(1)), "{s:?}");
        assert!(s.cost_ratio < 0.1 && s.variance_ratio < 1.1, "{s:?}");
        let sharp = vec![pixel(8, 1.0, [3.0, 9.0, 27.0], [2.0, 1.0], (10.0, 40.0, 160.0)); 4];
        assert_eq!(choose(&sharp, Some(4), false).0, ImageSplit::fine(Some(4)));
        // Without straight-light samples only K is chosen.
        let s = choose(&smooth, None, false).0;
        assert_eq!((s.march_factor, s.direct_samples), (8, None));
        // Non-finite statistics keep the fine march.
        let bad = vec![pixel(8, f64::NAN, [0.0; 3], [0.0; 2], (1.0, 1.0, 1.0))];
        assert_eq!(choose(&bad, Some(4), true), (ImageSplit::fine(Some(4)), Vec::new()));
        assert_eq!(choose(&[], Some(4), true).0, ImageSplit::fine(Some(4)));
    }

    /// The coarse march's added variance is the spread of the subset estimators:
    /// eight points alternating 0, 1 have coarse estimators (K = 2) 0 and 8
    /// around the fine 4, so they add 16; constant points add nothing.
    #[test]
    fn march_spread_is_the_subsets_spread() {
        let mut m = MarchSpread::default();
        for n in 0..8 {
            m.add(n, Rgb::splat(if n % 2 == 0 { 0.0 } else { 1.0 }), (1.0, None), (2, 0));
        }
        let mut p = PixelSpread::default();
        p.add((Rgb::splat(4.0), Rgb::splat(4.0)), 3, &m);
        assert!((p.march_added[0] - 16.0).abs() < 1e-12, "{:?}", p.march_added);
        assert_eq!(p.fixed_rays, 3.0);
        assert_eq!(p.point_rays, 8.0 * (2.0 + POINT_COST));
        let mut flat = MarchSpread::default();
        for n in 0..8 {
            flat.add(n, Rgb::splat(0.5), (1.0, None), (1, 0));
        }
        let mut q = PixelSpread::default();
        q.add((Rgb::splat(4.0), Rgb::splat(4.0)), 0, &flat);
        assert!(q.march_added.iter().all(|a| a.abs() < 1e-24), "{:?}", q.march_added);
    }

    /// The march share's predictions follow N·Var = (V − V_m) + m·V_m, the
    /// medium's m·V_m, the cost fixed + march / m; the choice itself keeps every
    /// sample marching.
    #[test]
    fn the_march_share_is_predicted() {
        // A march no coarser step serves (its points disagree), 4% of the cost
        // before it, the medium 5% of the variance.
        let mut p = pixel(8, 1.0, [3.0, 9.0, 27.0], [0.0; 2], (4.0, 96.0, 0.0));
        p.y_medium.1 = 7.0 * 0.05;
        let (s, all) = choose(&vec![p; 3], None, false);
        assert_eq!(s, ImageSplit::fine(None));
        let m4 = all.iter().find(|c| c.march_every == 4 && c.march_factor == 1).unwrap();
        assert!((m4.variance_ratio - (1.0 + 3.0 * 0.05)).abs() < 1e-12, "{m4:?}");
        assert!((m4.medium_variance_ratio - 4.0).abs() < 1e-12, "{m4:?}");
        assert!((m4.cost_ratio - (4.0 + 96.0 / 4.0) / 100.0).abs() < 1e-12, "{m4:?}");
        assert_eq!(all.len(), MARCH_FACTORS.len() * MARCH_EVERY.len());
    }

    /// Asked to (`share`), the choice takes the share of least (image ratio +
    /// medium ratio) × cost for the (K, n) it chose: with the surface 95% of the
    /// variance and the march 96% of the cost, J(m) = (1 + 0.05(m − 1) + m) ×
    /// (4 + 96/m)/100 is 2, 1.59, 1.44, 1.50, 1.78 at m = 1 … 16, so m = 4. Where
    /// the medium is all of the variance, J = 2(4m + 96)/100 grows with m: none.
    #[test]
    fn a_share_is_chosen_by_both_parts_errors_at_equal_time() {
        let mut p = pixel(8, 1.0, [3.0, 9.0, 27.0], [0.0; 2], (4.0, 96.0, 0.0));
        p.y_medium.1 = 7.0 * 0.05;
        let (s, all) = choose(&vec![p; 3], None, true);
        assert_eq!((s.march_factor, s.march_every), (1, 4), "{s:?}");
        let shared = |m| *all.iter().find(|c| c.march_factor == 1 && c.march_every == m).unwrap();
        for (m, j) in [(1, 2.0), (2, 1.586), (4, 1.442), (8, 1.496), (16, 1.775)] {
            assert!((share_cost(&shared(m)) - j).abs() < 1e-3, "m = {m}: {:?}", shared(m));
        }
        assert_eq!(choose(&vec![p; 3], None, false).0.march_every, 1);
        // All of the variance the medium's: every sample keeps marching.
        p.y_medium.1 = p.y.1;
        assert_eq!(choose(&vec![p; 3], None, true).0, ImageSplit::fine(None));
        // A coarser march chosen first, the share is that march's.
        let smooth = vec![pixel(8, 1.0, [0.01, 0.02, 0.04], [0.001, 0.0005], (10.0, 40.0, 160.0)); 4];
        let (s, _) = choose(&smooth, Some(4), true);
        let unshared = choose(&smooth, Some(4), false).0;
        assert_eq!(
            (s.march_factor, s.direct_samples),
            (unshared.march_factor, unshared.direct_samples)
        );
        assert!(share_cost(&s) <= share_cost(&unshared), "{s:?} {unshared:?}");
    }

    #[test]
    fn marched_samples_follow_the_share() {
        let every = |m| ImageSplit {
            march_every: m,
            ..ImageSplit::fine(None)
        };
        let s = every(4);
        let marched: Vec<u32> = (0..70).filter(|&k| marches(k, 3, &s)).collect();
        let runs: Vec<u32> = (0..8).chain(32..40).chain(64..70).collect();
        assert_eq!(marched, runs);
        for done in 0..100 {
            assert_eq!(
                marched_samples(done, 3, &s),
                (0..done).filter(|&k| marches(k, 3, &s)).count() as u32
            );
        }
        assert_eq!(marched_samples(9, 3, &every(1)), 9);
    }

    /// The marched samples stratify the pixel as all of them do: their positions
    /// (the first two draws of a pixel's scrambled Sobol' set) fill every eighth
    /// of it in x and in y alike. A stride (every fourth sample) would leave three
    /// quarters of the pixel to the unmarched samples.
    #[test]
    fn the_marched_samples_stratify_the_pixel() {
        use crate::pipeline::path::Sampling;
        let s = ImageSplit {
            march_every: 4,
            ..ImageSplit::fine(None)
        };
        for pixel in 0..20u64 {
            let (mut xs, mut ys) = ([0u32; 8], [0u32; 8]);
            for k in (4..256).filter(|&k| marches(k, 4, &s)) {
                let mut r = Sampling::Stratified.stream(7, pixel, k as u64);
                xs[(r.next_f64() * 8.0) as usize] += 1;
                ys[(r.next_f64() * 8.0) as usize] += 1;
            }
            // 60 marched samples beyond the first four: 7 or 8 in every eighth.
            for counts in [xs, ys] {
                assert!(
                    counts.iter().all(|&c| (7..=8).contains(&c)),
                    "pixel {pixel}: {counts:?}"
                );
            }
        }
    }

    #[test]
    fn a_shared_march_costs_its_fixed_part_and_a_share_of_the_march() {
        assert!((shared_cost_ratio(4, 100, 4) - 0.28).abs() < 1e-12);
        assert_eq!(shared_cost_ratio(4, 100, 1), 1.0);
        assert_eq!(shared_cost_ratio(0, 0, 8), 1.0);
        assert_eq!(shared_cost_ratio(7, 5, 8), 1.0);
    }

    #[test]
    fn equal_cost_samples_are_bounded() {
        let s = |c| ImageSplit {
            cost_ratio: c,
            ..ImageSplit::fine(None)
        };
        assert_eq!(equal_cost_samples(56, &s(0.25)), 224);
        assert_eq!(equal_cost_samples(56, &s(1e-9)), 56 * 16);
        assert_eq!(equal_cost_samples(56, &s(2.0)), 56);
    }
}
