//! The window's background: filled once a frame by the clear that starts it, never by its
//! panels.
//!
//! Under software rendering (Mesa llvmpipe, as on a line PC without a GPU) what a frame costs
//! is the pixels it shades: every triangle egui draws is textured and blended pixel by pixel,
//! while the clear before the frame is a plain memory fill. egui's panels each paint their own
//! fill, so the window's every pixel was shaded about twice a frame before anything on it was
//! drawn (the telemetry view at 1200×780: 1.8 window areas a frame; the central panel alone
//! 0.78, a panel inside it 0.31). Instead the window is cleared to the panels' colour
//! ([`clear_color`]) and each panel is drawn with no fill ([`bar`], [`central`]): the same
//! picture, 0.5 window areas a frame. Measured from outside with `.ci/window_cpu.sh` (release
//! build, telemetry polled at 50 Hz, redrawn at [`super::repaint::LIVE`]): a median of 29.7 %
//! of a core before (5 runs, 29.3-32.1), 21.9 % after (10 runs, 18.3-23.6); in a profile the
//! shader code llvmpipe compiles went from 55 % of the window's CPU to 36 %.

use eframe::egui;

/// The colour the window is cleared to before each frame: the panels' fill of `visuals`
/// (opaque), as linear-in-gamma RGBA in 0..=1, which eframe's `App::clear_color` returns.
pub fn clear_color(visuals: &egui::Visuals) -> [f32; 4] {
    visuals.panel_fill.to_normalized_gamma_f32()
}

/// A top, bottom or side panel's frame (egui's own margins and separator line) without its
/// fill, which the clear has already painted.
pub fn bar(style: &egui::Style) -> egui::Frame {
    egui::Frame::side_top_panel(style).fill(egui::Color32::TRANSPARENT)
}

/// The central panel's frame (egui's own margins) without its fill.
pub fn central(style: &egui::Style) -> egui::Frame {
    egui::Frame::central_panel(style).fill(egui::Color32::TRANSPARENT)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clear_is_the_panels_colour_and_the_panels_paint_nothing_under_their_content() {
        for visuals in [egui::Visuals::dark(), egui::Visuals::light()] {
            let style = egui::Style {
                visuals: visuals.clone(),
                ..Default::default()
            };
            assert_eq!(
                clear_color(&visuals),
                visuals.panel_fill.to_normalized_gamma_f32()
            );
            assert_eq!(clear_color(&visuals)[3], 1.0, "an opaque clear");
            for frame in [bar(&style), central(&style)] {
                assert_eq!(frame.fill, egui::Color32::TRANSPARENT);
            }
            // Margins and the separator line stay egui's own.
            assert_eq!(
                bar(&style).inner_margin,
                egui::Frame::side_top_panel(&style).inner_margin
            );
            assert_eq!(
                bar(&style).stroke,
                egui::Frame::side_top_panel(&style).stroke
            );
            assert_eq!(
                central(&style).inner_margin,
                egui::Frame::central_panel(&style).inner_margin
            );
        }
    }
}
