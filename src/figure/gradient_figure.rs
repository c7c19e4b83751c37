//! The paper's gradient figure (Marco et al. 2018, the figure of 2D single and
//! multiple scattering gradients of an occluder with a light above it): per method
//! a panel where each sample's gradient ∇L is colour-coded — hue = direction,
//! brightness = log |∇L| — plus a colour-wheel legend, and the profile of the
//! gradient along a line as stacked line plots.
//!
//! Conventions (the colour code itself: [`gradient_color`](mod@super::gradient_color)):
//! - Samples lie on a regular grid; its spacing is inferred per panel from the
//!   sample positions ([`grid_spacing`]), so panels may differ in resolution.
//!   Each sample owns the cell of that size centred on it.
//! - One magnitude range is shared by all panels of a figure ([`magnitude_range`]).
//! - Arrows are 0.8 cells long; on grids finer than ~9 px per cell only every k-th
//!   sample in each direction gets one (k cells long, for the k × k block). Over
//!   cells they are drawn dark; on the bare background in their colour.
//! - The sampling line is dotted black on white, readable on any colour; a small
//!   disc marks its start (s = 0 in [`gradient_line_plot`]).
//! - Paper colours for the profiles: reference blue, unaware (Jarosz et al. 2008)
//!   orange, aware (ours) purple.

use super::colorbar::short_sci;
use super::gradient_color::{
    GradientSample, PANEL_BACKGROUND, colour_wheel_legend, gradient_color, grid_spacing, magnitude_range,
};
use super::overlay::{OverlayStyle, draw_scene};
use super::panel::{Canvas, View};
use super::plot::{Axis, Plot, Series, draw_plots_stacked};
use super::text::{HAlign, VAlign, draw_text_aligned, text_width};
use crate::flatland::scene::Scene;
use glam::DVec2;
use tiny_skia::{Color, Paint, Pixmap, Rect, Transform};

/// How a gradient panel shows its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GradientStyle {
    /// One arrow per sample on a dark background.
    Arrows,
    /// Each sample fills its grid cell (as in the paper).
    Cells,
    /// Cells with dark arrows on top.
    CellsAndArrows,
}

/// The paper's colours for the gradient profiles.
pub const REFERENCE_BLUE: [u8; 3] = [31, 119, 180];
pub const UNAWARE_ORANGE: [u8; 3] = [255, 127, 14];
pub const AWARE_PURPLE: [u8; 3] = [148, 103, 189];

const TEXT: [u8; 4] = [20, 20, 20, 255];

/// One method's gradient along the sampling line: (label, colour, [(s, ∇L)]).
pub type GradientProfile = (String, [u8; 3], Vec<(f64, DVec2)>);

fn fill_rect(pixmap: &mut Pixmap, x: f32, y: f32, w: f32, h: f32, c: [u8; 3]) {
    if let Some(r) = Rect::from_xywh(x, y, w, h) {
        let mut paint = Paint::default();
        paint.set_color(Color::from_rgba8(c[0], c[1], c[2], 255));
        paint.anti_alias = false;
        pixmap.fill_rect(r, &paint, Transform::identity(), None);
    }
}

/// Draw one gradient panel into `view` (which it fills): the samples in `style` on a
/// dark background, the scene, and the sampling `line` (world end points).
pub fn gradient_panel(
    pixmap: &mut Pixmap,
    view: &View,
    samples: &[GradientSample],
    scene: Option<&Scene>,
    magnitude_range: (f64, f64),
    line: Option<(DVec2, DVec2)>,
    style: GradientStyle,
) {
    let (vx0, vy0) = (view.x0.round(), view.y0.round());
    let (vx1, vy1) = ((view.x0 + view.width).round(), (view.y0 + view.height).round());
    fill_rect(pixmap, vx0, vy0, vx1 - vx0, vy1 - vy0, PANEL_BACKGROUND);
    let spacing = grid_spacing(samples).unwrap_or((view.world_max - view.world_min) / 16.0);
    if style != GradientStyle::Arrows {
        for s in samples {
            let (a, b) = (view.to_pixel(s.at - 0.5 * spacing), view.to_pixel(s.at + 0.5 * spacing));
            let (x0, x1) = (a.0.round().max(vx0), b.0.round().min(vx1));
            let (y0, y1) = (b.1.round().max(vy0), a.1.round().min(vy1));
            if x1 > x0 && y1 > y0 {
                fill_rect(
                    pixmap,
                    x0,
                    y0,
                    x1 - x0,
                    y1 - y0,
                    gradient_color(s.grad, magnitude_range),
                );
            }
        }
    }
    if style != GradientStyle::Cells {
        draw_arrows(pixmap, view, samples, spacing, magnitude_range, style);
    }
    let u = OverlayStyle::for_panel(view.width.max(view.height));
    if let Some(scene) = scene {
        draw_scene(pixmap, scene, view, &u);
    }
    if let Some((a, b)) = line {
        let mut canvas = Canvas::new(pixmap, view, 10.0);
        let (a, b) = (view.to_pixel_f64(a), view.to_pixel_f64(b));
        let w = 2.2 * u.scale;
        canvas.line(a, b, w, [255, 255, 255, 255]);
        canvas.polyline(&[a, b], false, w, [0, 0, 0, 255], Some((1.2 * w, 1.2 * w)));
        canvas.disc(a, 2.6 * w, [255, 255, 255, 255]);
        canvas.disc(a, 1.7 * w, [0, 0, 0, 255]);
    }
}

fn draw_arrows(
    pixmap: &mut Pixmap,
    view: &View,
    samples: &[GradientSample],
    spacing: DVec2,
    range: (f64, f64),
    style: GradientStyle,
) {
    let size = view.world_max - view.world_min;
    let cell_px = (spacing.x / size.x * view.width as f64).min(spacing.y / size.y * view.height as f64);
    let stride = (9.0 / cell_px).ceil().max(1.0) as i64;
    let length = 0.8 * stride as f64 * cell_px;
    let width = (0.09 * length).clamp(1.0, 3.0) as f32;
    let origin = samples
        .iter()
        .map(|s| s.at)
        .filter(|p| p.is_finite())
        .reduce(DVec2::min)
        .unwrap_or_default();
    let mut canvas = Canvas::new(pixmap, view, length);
    for s in samples {
        let index = ((s.at - origin) / spacing).round();
        if index.x as i64 % stride != 0 || index.y as i64 % stride != 0 || !s.grad.is_finite() {
            continue;
        }
        let d = view.direction_to_pixel(s.grad);
        if d == DVec2::ZERO {
            continue;
        }
        let color = match style {
            GradientStyle::CellsAndArrows => [0, 0, 0, 200],
            _ => {
                let [r, g, b] = gradient_color(s.grad, range);
                [r, g, b, 255]
            }
        };
        // The centre of the stride × stride block the arrow stands for.
        let c = view.to_pixel_f64(s.at + 0.5 * (stride - 1) as f64 * spacing);
        let (tail, tip) = (c - 0.5 * length * d, c + 0.5 * length * d);
        let head = 0.38 * length;
        let base = tip - head * d;
        canvas.line(tail, base + 0.3 * head * d, width, color);
        canvas.polygon(
            &[tip, base + 0.55 * head * d.perp(), base - 0.55 * head * d.perp()],
            color,
        );
    }
}

/// Panels side by side, one per (caption, samples), with one shared magnitude range
/// and one colour wheel; see the module documentation. The world shown is the
/// scene's domain; each panel's longest side is about 360 px (a whole number of
/// pixels per grid cell when the grid tiles the domain).
pub fn gradient_figure(
    panels: &[(String, Vec<GradientSample>)],
    scene: &Scene,
    line: Option<(DVec2, DVec2)>,
    style: GradientStyle,
    title: Option<&str>,
) -> Pixmap {
    let (wmin, wmax) = (scene.domain_min, scene.domain_max);
    let size = wmax - wmin;
    let longest = 360.0f32;
    let aspect = (size.x / size.y) as f32;
    let (mut pw, mut ph) = if aspect >= 1.0 {
        (longest, (longest / aspect).round())
    } else {
        ((longest * aspect).round(), longest)
    };
    // A whole number of pixels per cell when the finest grid tiles the domain.
    let finest = panels.iter().filter_map(|(_, s)| grid_spacing(s)).reduce(DVec2::min);
    if let Some(sp) = finest {
        let cells = size / sp;
        if (cells - cells.round()).abs().max_element() < 1e-6 && cells.max_element() <= longest as f64 {
            let k = (longest as f64 / cells.max_element()).round().max(1.0);
            (pw, ph) = ((cells.x.round() * k) as f32, (cells.y.round() * k) as f32);
        }
    }
    let range = magnitude_range(panels.iter().flat_map(|(_, s)| s));

    let (margin, gap, caption_px, title_px) = (16.0f32, 14.0f32, 14.0f32, 17.0f32);
    let top = if title.is_some() {
        (2.4 * title_px).round()
    } else {
        margin
    };
    let caption_h = (2.0 * caption_px).round();
    let radius = (0.22 * ph).clamp(40.0, 80.0).round();
    let legend_font = (0.2 * radius).clamp(10.0, 16.0).round();
    let range_lines = [
        format!("centre: |∇L| ≤ {}", short_sci(range.0)),
        format!("rim: |∇L| ≥ {}", short_sci(range.1)),
    ];
    let legend_w = [
        text_width("direction / log |∇L|", legend_font),
        2.0 * radius + 2.0 * text_width("+x", legend_font) + legend_font,
    ]
    .into_iter()
    .chain(range_lines.iter().map(|l| text_width(l, legend_font)))
    .fold(0.0, f32::max)
    .ceil();
    let n = panels.len().max(1) as f32;
    let width = (margin + n * pw + (n - 1.0) * gap + 2.0 * gap + legend_w + margin).ceil();
    let height = (top + caption_h + ph + margin).ceil();
    let mut pixmap = Pixmap::new(width as u32, height as u32).expect("figure size");
    pixmap.fill(Color::WHITE);

    if let Some(t) = title {
        let size = (title_px * ((width - 2.0 * margin) / text_width(t, title_px)).min(1.0)).max(6.0);
        draw_text_aligned(
            &mut pixmap,
            t,
            0.5 * width,
            0.55 * top,
            size,
            TEXT,
            HAlign::Center,
            VAlign::Middle,
        );
    }
    let py = top + caption_h;
    for (k, (caption, samples)) in panels.iter().enumerate() {
        let px = margin + k as f32 * (pw + gap);
        let view = View::new(wmin, wmax, px, py, pw, ph);
        gradient_panel(&mut pixmap, &view, samples, Some(scene), range, line, style);
        let size = (caption_px * (pw / text_width(caption, caption_px)).min(1.0)).max(6.0);
        draw_text_aligned(
            &mut pixmap,
            caption,
            px + 0.5 * pw,
            py - 0.45 * caption_h,
            size,
            TEXT,
            HAlign::Center,
            VAlign::Middle,
        );
    }
    let lx = margin + n * pw + (n - 1.0) * gap + 2.0 * gap;
    let (cx, cy) = ((lx + 0.5 * legend_w).round(), (py + 0.4 * ph).round());
    colour_wheel_legend(&mut pixmap, cx, cy, radius);
    let line_h = (1.35 * legend_font).round();
    let y = cy + radius + (0.6 * legend_font).round() + 2.0 * line_h;
    for (i, l) in range_lines.iter().enumerate() {
        draw_text_aligned(
            &mut pixmap,
            l,
            cx,
            y + i as f32 * line_h,
            legend_font,
            [70, 70, 70, 255],
            HAlign::Center,
            VAlign::Top,
        );
    }
    pixmap
}

/// The gradient along the sampling line: per method (label, colour, [(s, ∇L)]) with
/// s ∈ [0, 1] from the line's start, three stacked plots sharing the s axis —
/// |∇L| (from 0), ∂L/∂x and ∂L/∂y — under `title`; 760 px wide, 230 px per plot.
pub fn gradient_line_plot(profiles: &[GradientProfile], title: &str) -> Pixmap {
    let (width, plot_h, title_px) = (760.0f32, 230.0f32, 17.0f32);
    let top = if title.trim().is_empty() {
        0.0
    } else {
        (2.2 * title_px).round()
    };
    let series = |f: fn(DVec2) -> f64| {
        profiles
            .iter()
            .map(|(label, color, pts)| Series::new(label, *color, pts.iter().map(|&(s, g)| (s, f(g))).collect()))
            .collect::<Vec<_>>()
    };
    let s_axis = |label: &str| Axis::linear(label).with_range(0.0, 1.0);
    let plot = |y: &str, x: &str, f: fn(DVec2) -> f64, legend: bool| Plot {
        title: None,
        x: s_axis(x),
        y: Axis::linear(y),
        series: series(f),
        width: width as u32,
        height: plot_h as u32,
        legend,
    };
    let mut plots = [
        plot("|∇L|", "", |g| g.length(), true),
        plot("∂L/∂x", "", |g| g.x, false),
        plot("∂L/∂y", "s (position along the line)", |g| g.y, false),
    ];
    // Magnitudes from 0, so that their ratios read off the plot.
    let top_magnitude = plots[0]
        .series
        .iter()
        .flat_map(|s| &s.points)
        .map(|p| p.1)
        .filter(|m| m.is_finite())
        .fold(0.0, f64::max);
    if top_magnitude > 0.0 {
        plots[0].y.range = Some((0.0, 1.05 * top_magnitude));
    }
    let height = top + 3.0 * plot_h;
    let mut pixmap = Pixmap::new(width as u32, height as u32).expect("plot size");
    pixmap.fill(Color::WHITE);
    if top > 0.0 {
        let size = (title_px * ((width - 24.0) / text_width(title, title_px)).min(1.0)).max(6.0);
        draw_text_aligned(
            &mut pixmap,
            title,
            0.5 * width,
            0.55 * top,
            size,
            TEXT,
            HAlign::Center,
            VAlign::Middle,
        );
    }
    draw_plots_stacked(
        &mut pixmap,
        (0.0, top, width, 3.0 * plot_h),
        &plots.iter().collect::<Vec<_>>(),
    );
    pixmap
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figure::colormap::angle_color;
    use std::f64::consts::{FRAC_PI_2, PI};

    const SCENE: &str = r#"{
        "domain": { "min": [-1, -1], "max": [1, 1] },
        "segments": [ { "name": "occluder", "a": [-0.4, 0.0], "b": [0.4, 0.0], "reflectance": 0.5 } ],
        "lights": [ { "type": "point", "position": [0.0, 0.5], "intensity": 1.0 } ],
        "medium": { "sigma_a": 0.05, "sigma_s": 0.5, "region": "domain" }
    }"#;

    fn rgb(p: &Pixmap, x: u32, y: u32) -> [u8; 3] {
        let c = p.pixel(x, y).unwrap();
        [c.red(), c.green(), c.blue()]
    }

    /// Samples at the centres of an n × n grid over [-1, 1]² with gradient f(p).
    fn grid(n: usize, f: impl Fn(DVec2) -> DVec2) -> Vec<GradientSample> {
        let h = 2.0 / n as f64;
        (0..n * n)
            .map(|k| {
                let at = DVec2::new(-1.0 + h * ((k % n) as f64 + 0.5), -1.0 + h * ((k / n) as f64 + 0.5));
                GradientSample { at, grad: f(at) }
            })
            .collect()
    }

    #[test]
    fn cells_take_the_angle_colour_of_their_direction() {
        // Three cells in a row: +x, +y, −x, equally strong (brightness 1).
        let dirs = [DVec2::X, DVec2::Y, -DVec2::X];
        let samples: Vec<_> = dirs
            .iter()
            .enumerate()
            .map(|(i, &d)| GradientSample {
                at: DVec2::new(i as f64 - 1.0, 0.0),
                grad: 2.0 * d,
            })
            .collect();
        let view = View::new(DVec2::new(-1.5, -0.5), DVec2::new(1.5, 0.5), 0.0, 0.0, 90.0, 30.0);
        let range = (0.1, 1.0);
        let mut cells = Pixmap::new(90, 30).unwrap();
        gradient_panel(&mut cells, &view, &samples, None, range, None, GradientStyle::Cells);
        let got: Vec<[u8; 3]> = (0..3).map(|i| rgb(&cells, 15 + 30 * i, 15)).collect();
        for (c, want) in got.iter().zip([0.0, FRAC_PI_2, PI]) {
            assert_eq!(*c, angle_color(want, 1.0));
        }
        assert!(got[0] != got[1] && got[1] != got[2] && got[0] != got[2]);
        // Arrows: each cell holds ink of its colour, the rest is background.
        let mut arrows = Pixmap::new(90, 30).unwrap();
        gradient_panel(&mut arrows, &view, &samples, None, range, None, GradientStyle::Arrows);
        for (i, c) in got.iter().enumerate() {
            let hits = (0..30u32)
                .flat_map(|y| (30 * i as u32..30 * i as u32 + 30).map(move |x| (x, y)))
                .filter(|&(x, y)| rgb(&arrows, x, y) == *c)
                .count();
            assert!(hits > 10, "arrow {i}: {hits}");
        }
        assert_eq!(rgb(&arrows, 1, 1), PANEL_BACKGROUND);
        // The +x arrow's head is on the right of its cell, the +y arrow's on top.
        let ink_at = |x0: u32, x1: u32, y0: u32, y1: u32| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| rgb(&arrows, x, y) != PANEL_BACKGROUND)
                .count()
        };
        assert!(ink_at(16, 28, 8, 22) > ink_at(2, 14, 8, 22));
        assert!(ink_at(38, 52, 2, 14) > ink_at(38, 52, 16, 28));
    }

    /// A light above an occluder in a medium: L = a bump around the light, darkened
    /// in the occluder's (soft) shadow; its gradient by central differences.
    fn radiance(p: DVec2, occluded: bool) -> f64 {
        let light = DVec2::new(0.0, 0.5);
        let bump = (-(p - light).length_squared() / 0.5).exp();
        if !occluded || p.y >= 0.05 {
            return bump;
        }
        // Where the ray to the light crosses y = 0, and the shadow's soft edges.
        let x0 = light.x + (p.x - light.x) * light.y / (light.y - p.y);
        let smooth = |a: f64, b: f64, x: f64| {
            let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        };
        let shadow = (1.0 - smooth(0.33, 0.47, x0.abs())) * smooth(0.05, -0.05, p.y);
        bump * (1.0 - 0.85 * shadow)
    }

    fn numeric_grad(p: DVec2, occluded: bool) -> DVec2 {
        let h = 1e-4;
        DVec2::new(
            radiance(p + DVec2::X * h, occluded) - radiance(p - DVec2::X * h, occluded),
            radiance(p + DVec2::Y * h, occluded) - radiance(p - DVec2::Y * h, occluded),
        ) / (2.0 * h)
    }

    /// The three methods of the paper's figure on the synthetic scene.
    fn methods(at: DVec2) -> [DVec2; 3] {
        let reference = numeric_grad(at, true);
        let unaware = numeric_grad(at, false);
        let aware = DVec2::from_angle(0.08 * (7.0 * at.x).sin()).rotate(reference) * (1.0 + 0.1 * (5.0 * at.y).cos());
        [aware, unaware, reference]
    }

    fn example_panels(n: usize) -> Vec<(String, Vec<GradientSample>)> {
        let g = grid(n, |_| DVec2::ZERO);
        ["aware (ours)", "unaware (Jarosz 2008)", "reference"]
            .iter()
            .enumerate()
            .map(|(m, name)| {
                let s = g
                    .iter()
                    .map(|s| GradientSample {
                        at: s.at,
                        grad: methods(s.at)[m],
                    })
                    .collect();
                (name.to_string(), s)
            })
            .collect()
    }

    fn example_profiles(line: (DVec2, DVec2)) -> Vec<GradientProfile> {
        let names = ["aware (ours)", "unaware (Jarosz 2008)", "reference"];
        let colors = [AWARE_PURPLE, UNAWARE_ORANGE, REFERENCE_BLUE];
        (0..3)
            .rev()
            .map(|m| {
                let pts = (0..=200)
                    .map(|i| {
                        let s = i as f64 / 200.0;
                        (s, methods(line.0.lerp(line.1, s))[m])
                    })
                    .collect();
                (names[m].to_string(), colors[m], pts)
            })
            .collect()
    }

    #[test]
    fn figure_has_the_expected_size_and_is_deterministic() {
        let scene = Scene::from_json(SCENE, "test").unwrap();
        let line = Some((DVec2::new(-1.0, -0.5), DVec2::new(1.0, -0.5)));
        let panels = example_panels(24);
        let three = gradient_figure(&panels, &scene, line, GradientStyle::Cells, Some("Gradients"));
        let two = gradient_figure(&panels[..2], &scene, line, GradientStyle::Cells, Some("Gradients"));
        // 24 cells of 15 px per panel, panels 14 px apart.
        assert_eq!(three.width() - two.width(), 360 + 14);
        assert!(three.height() > 360 && three.height() < 460, "{}", three.height());
        assert_eq!(
            three.data(),
            gradient_figure(&panels, &scene, line, GradientStyle::Cells, Some("Gradients")).data()
        );
        // A cell of the reference panel away from marks has its colour in the shared range.
        let range = magnitude_range(panels.iter().flat_map(|(_, s)| s));
        let py = (0..three.height()).find(|&y| rgb(&three, 17, y) != [255; 3]).unwrap();
        let (i, j) = (3usize, 20usize); // column 3, row 20 from the top
        let s = &panels[2].1[(23 - j) * 24 + i];
        let c = rgb(&three, 16 + 2 * (360 + 14) + 15 * i as u32 + 7, py + 15 * j as u32 + 7);
        assert_eq!(c, gradient_color(s.grad, range));
    }

    #[test]
    fn line_plot_has_ink_for_each_method() {
        let profiles = example_profiles((DVec2::new(-1.0, -0.5), DVec2::new(1.0, -0.5)));
        let p = gradient_line_plot(&profiles, "Gradient along the line");
        assert_eq!((p.width(), p.height()), (760, 690 + 37));
        for c in [REFERENCE_BLUE, UNAWARE_ORANGE, AWARE_PURPLE] {
            let n = p
                .pixels()
                .iter()
                .filter(|q| [q.red(), q.green(), q.blue()] == c)
                .count();
            assert!(n > 100, "{c:?}: {n}");
        }
    }

    /// With `VOLCACHE_FIGURE_OUT=dir`, writes `gradient_example.png` (cells),
    /// `gradient_example_arrows.png` (cells and arrows), `gradient_example_fine_arrows.png`
    /// (arrows on a 64² grid, every other sample) and `gradient_profile_example.png`.
    #[test]
    fn example_gradient_figures() {
        let scene = Scene::from_json(SCENE, "test").unwrap();
        let line = (DVec2::new(-0.95, -0.55), DVec2::new(0.95, -0.55));
        let title = Some("Single-scattering gradient ∇L_s: occluder under a point light");
        let cells = gradient_figure(&example_panels(32), &scene, Some(line), GradientStyle::Cells, title);
        let arrows = gradient_figure(
            &example_panels(24),
            &scene,
            Some(line),
            GradientStyle::CellsAndArrows,
            title,
        );
        let fine = gradient_figure(&example_panels(64), &scene, Some(line), GradientStyle::Arrows, title);
        let profile = gradient_line_plot(&example_profiles(line), "∇L_s along the dotted line");
        if let Some(dir) = std::env::var_os("VOLCACHE_FIGURE_OUT") {
            let dir = std::path::Path::new(&dir);
            crate::output::write_png(&dir.join("gradient_example.png"), &cells).unwrap();
            crate::output::write_png(&dir.join("gradient_example_arrows.png"), &arrows).unwrap();
            crate::output::write_png(&dir.join("gradient_profile_example.png"), &profile).unwrap();
            crate::output::write_png(&dir.join("gradient_example_fine_arrows.png"), &fine).unwrap();
        }
    }
}
