//! The march step of a cached render's camera samples beyond the placed ones
//! (`CachedRenderParams::image_march_step`): on a foggy room of our own, a coarser
//! march over the same records makes the extra samples cheaper and leaves the
//! image's expectation where it was; the placed samples never change.

mod room3d;

use room3d::ROOM;
use std::path::Path;
use volcache::core::color::luminance;
use volcache::core::metric::CacheMethod;
use volcache::progress::Progress;
use volcache::volume::cached::{
    CacheSettings, CachedRender, CachedRenderParams, RecordMemo, default_eps, render_cached,
};
use volcache::volume::render::RenderParams;
use volcache::volume::scene::Scene;

fn room() -> Scene {
    Scene::from_json(ROOM, "<room3d>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// 32×24, `spp` camera samples of which 4 are placed, march step scene / 64.
fn params(scene: &Scene, spp: u32, image_step: Option<f64>) -> CachedRenderParams {
    let mut p = CachedRenderParams::from_scene(scene);
    (p.image.width, p.image.height, p.image.spp, p.image.seed) = (32, 24, spp, 5);
    p.march_step = scene.scale / 64.0;
    p.place_spp = Some(4);
    p.image_march_step = image_step.map(|k| k * p.march_step);
    p
}

fn render(scene: &Scene, p: &CachedRenderParams, memo: &mut RecordMemo) -> CachedRender {
    let mut cs = CacheSettings::new::<volcache::core::space::D3>(
        CacheMethod::Ours,
        default_eps(CacheMethod::Ours, scene),
        RenderParams::from_scene(scene).first_vertex_settings(),
    );
    cs.probe.rays = 1024;
    cs.probe.steps = 12;
    render_cached(scene, p, &cs, None, memo, &Progress::new()).unwrap()
}

/// With 8× the march step for samples 4..64, the same records give an image
/// whose medium part has the same mean (within 3 standard errors of the pixels'
/// differences, which only the march's noise makes: the records are shared), at
/// a fraction of the reconstruction's ray tests. Measured: see the printout.
#[test]
fn a_coarser_image_march_is_cheaper_and_keeps_the_expectation() {
    let s = room();
    let mut memo = RecordMemo::new();
    let fine = render(&s, &params(&s, 64, None), &mut memo);
    let coarse = render(&s, &params(&s, 64, Some(8.0)), &mut memo);
    assert_eq!(fine.placement.record_count(), coarse.placement.record_count());
    let (a, b) = (&fine.reconstruction.image, &coarse.reconstruction.image);
    let d: Vec<f64> = a
        .medium
        .iter()
        .zip(&b.medium)
        .map(|(x, y)| luminance(*y) - luminance(*x))
        .collect();
    let n = d.len() as f64;
    let mean_d = d.iter().sum::<f64>() / n;
    let se = (d.iter().map(|v| (v - mean_d).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    let mean_a = a.medium.iter().map(|c| luminance(*c)).sum::<f64>() / n;
    println!(
        "medium mean {mean_a:.5}, coarse − fine {mean_d:+.2e} ± {se:.1e}; rays {} fine, {} coarse; uncovered {} / {}",
        a.rays, b.rays, fine.reconstruction.uncovered, coarse.reconstruction.uncovered
    );
    assert!(mean_d.abs() < 3.0 * se + 2e-3 * mean_a, "{mean_d} ± {se}");
    assert!(se > 0.0, "the coarse march changed nothing");
    assert!((b.rays as f64) < 0.5 * a.rays as f64, "{} vs {}", b.rays, a.rays);
}

/// Samples placement visited keep the placement's march: with no sample beyond
/// them, the image is the same bit for bit whatever the image march step.
#[test]
fn the_placed_samples_keep_their_march() {
    let s = room();
    let mut memo = RecordMemo::new();
    let a = render(&s, &params(&s, 4, None), &mut memo);
    let b = render(&s, &params(&s, 4, Some(8.0)), &mut memo);
    assert_eq!(a.reconstruction.image.values, b.reconstruction.image.values);
}
