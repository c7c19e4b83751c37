use std::path::Path;
use volcache::core::color::luminance;
use volcache::core::metric::CacheMethod;
use volcache::core::stats::ImageErrors;
use volcache::progress::Progress;
use volcache::volume::cached::*;
use volcache::volume::render::{RenderParams, render};
use volcache::volume::scene::Scene;

fn err(a: &[volcache::core::color::Rgb], b: &[volcache::core::color::Rgb]) -> ImageErrors {
    let p: Vec<(f64, f64)> = a.iter().zip(b).map(|(x, y)| (luminance(*x), luminance(*y))).collect();
    ImageErrors::of_luminance_pairs(&p)
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let s = Scene::load(Path::new(&a[1])).unwrap();
    let w: usize = a[2].parse().unwrap();
    let h: usize = a[3].parse().unwrap();
    let rays: usize = a[4].parse().unwrap();
    let steps: usize = a[5].parse().unwrap();
    let target: usize = a[6].parse().unwrap();
    let ref_spp: u32 = a[7].parse().unwrap();
    let spp: u32 = a[8].parse().unwrap();
    let mut rp = RenderParams::from_scene(&s);
    (rp.width, rp.height) = (w, h);
    rp.spp = ref_spp;
    rp.seed = 99;
    let t = std::time::Instant::now();
    let reference = render(&s, &rp, &Progress::new()).unwrap();
    println!("reference {} spp: {:.1}s, rel se {:.4}", ref_spp, t.elapsed().as_secs_f64(), reference.relative_std_error());
    let mut pp = CachedRenderParams::from_scene(&s);
    pp.image = RenderParams { spp, seed: 1, ..rp.clone() };
    if a.len() > 9 { pp.march_step = a[9].parse().unwrap(); }
    let t = std::time::Instant::now();
    let mref = march_reference(&s, &pp, ref_spp, &Progress::new()).unwrap();
    println!("march reference {} paths: {:.1}s; vs pt ref: medium RMSE {:.4e}", ref_spp, t.elapsed().as_secs_f64(), err(&mref.image.medium, &reference.medium).rmse);
    let mref2 = march_reference(&s, &pp, ref_spp, &Progress::new()).unwrap();
    let t = std::time::Instant::now();
    let pt = render(&s, &RenderParams { spp: 64, seed: 5, ..rp.clone() }, &Progress::new()).unwrap();
    println!("pt 64spp {:.2}s: total {:?} medium {:?}", t.elapsed().as_secs_f64(), err(&pt.values, &reference.values).rmse, err(&pt.medium, &reference.medium).rmse);
    for m in [CacheMethod::Ours, CacheMethod::Jarosz08] {
        let mut cs = CacheSettings::new(m, CacheSettings::default_eps(m, &s));
        cs.probe.rays = rays;
        cs.probe.steps = steps;
        let mut memo = RecordMemo::new();
        let t = std::time::Instant::now();
        let r = render_cached(&s, &pp, &cs, Some(target), &mut memo, &Progress::new()).unwrap();
        let im = &r.reconstruction.image;
        println!("   vs march reference: total {:.4e} medium {:.4e}", err(&im.values, &mref.image.values).rmse, err(&im.medium, &mref.image.medium).rmse);
        println!("{m:?}: {} records eps {:.3e} in {:.1}s (placement {:.2}s, recon {:.2}s, {} queries, uncovered {}), rays {:.2e}; RMSE total {:.4e} medium {:.4e} (mean ref medium {:.4e})",
            r.placement.cache.len(), r.placement.eps, t.elapsed().as_secs_f64(), r.placement.seconds, im.seconds, r.placement.query_points, r.reconstruction.uncovered, r.rays() as f64,
            err(&im.values, &reference.values).rmse, err(&im.medium, &reference.medium).rmse, err(&im.medium, &reference.medium).mean_reference);
        let radii: Vec<f64> = r.placement.records().iter().map(|x| x.radii.iter().cloned().fold(0.0, f64::max)).collect();
        let mut rs = radii.clone(); rs.sort_by(|a,b| a.partial_cmp(b).unwrap());
        if !rs.is_empty() { println!("   radii min {:.3} med {:.3} max {:.3}", rs[0], rs[rs.len()/2], rs[rs.len()-1]); }
    }
}
