//! How the window's width is shared: the side panels give way so that the canvas
//! keeps a usable minimum (issue 15: at 1024×700 with the probe inspector open the
//! canvas was ~150 px wide, at 800×500 it vanished). Pure arithmetic, tested here;
//! the panels' Show toggles in the toolbar collapse them entirely.

/// The canvas never gets narrower than this while a side panel could give way.
pub const MIN_CANVAS_WIDTH: f32 = 360.0;
/// The side panels' preferred widths (controls, inspector), including margins.
pub const CONTROLS_WIDTH: f32 = 300.0;
pub const INSPECTOR_WIDTH: f32 = 400.0;
/// Below this a panel is not worth showing; it stays at least this wide while on.
const MIN_PANEL_WIDTH: f32 = 140.0;

/// The largest widths of the controls and the inspector (0 when hidden) in a
/// window `width` points wide: their preferred widths while the canvas keeps
/// [`MIN_CANVAS_WIDTH`], else the room beyond it shared in proportion.
pub fn panel_max_widths(width: f32, controls: bool, inspector: bool) -> (f32, f32) {
    let want = [
        if controls { CONTROLS_WIDTH } else { 0.0 },
        if inspector { INSPECTOR_WIDTH } else { 0.0 },
    ];
    let total = want[0] + want[1];
    if total == 0.0 {
        return (0.0, 0.0);
    }
    let room = (width - MIN_CANVAS_WIDTH).max(0.0);
    let k = (room / total).min(1.0);
    let share = |w: f32| if w > 0.0 { (w * k).max(MIN_PANEL_WIDTH) } else { 0.0 };
    (share(want[0]), share(want[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_give_way_to_the_canvas() {
        // Wide: both at their preferred widths.
        assert_eq!(panel_max_widths(1280.0, true, true), (300.0, 400.0));
        // 1024: the canvas keeps its minimum, the panels share the rest 3:4.
        let (c, i) = panel_max_widths(1024.0, true, true);
        assert!((1024.0 - c - i - MIN_CANVAS_WIDTH).abs() < 1e-3 && (i / c - 4.0 / 3.0).abs() < 1e-4);
        // 800 with the inspector hidden: the controls alone.
        assert_eq!(panel_max_widths(800.0, true, false), (300.0, 0.0));
        // Tiny windows: each shown panel keeps a usable minimum.
        assert_eq!(panel_max_widths(300.0, true, true), (140.0, 140.0));
        assert_eq!(panel_max_widths(300.0, false, false), (0.0, 0.0));
    }
}
