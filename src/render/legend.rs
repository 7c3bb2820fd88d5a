//! The colour-map legend: a vertical viridis bar (maximum at the top) with
//! the field name above it and tick values beside it, drawn on the CPU into
//! a strip at the right of the view grid. A field of a few whole numbers
//! (piece or group ids, depths) gets one swatch per value instead.

use super::colormap::sample_srgb8;
use super::text::{draw_text, fill_rect, text_height, text_width};
use super::{Image, color_coord};

/// Text scale of legend labels (8×8 glyphs drawn 16×16).
const SCALE: u32 = 2;
/// Outer padding of the strip, pixels.
const PAD: u32 = 10;
/// Bar width, tick length and the gap before a label, pixels.
const BAR_W: u32 = 24;
const TICK: u32 = 6;
const GAP: u32 = 4;
/// Label and outline colour.
pub(crate) const INK: [u8; 4] = [30, 30, 30, 255];

/// Most values a legend lists as swatches.
pub(crate) const MAX_CATEGORIES: usize = 16;
/// Gap between swatch rows, pixels.
const ROW_GAP: u32 = 6;

/// What the legend shows: the field name, the range mapped to 0 and 1 and,
/// for a field of a few whole numbers, those values (ascending; empty for
/// a continuous field).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Legend {
    pub name: String,
    pub lo: f32,
    pub hi: f32,
    pub categories: Vec<f32>,
}

impl Legend {
    /// The row pitch of the swatches when the field is categorical and they
    /// fit into a strip `height` tall (else the continuous bar is drawn).
    fn swatch_pitch(&self, height: u32) -> Option<u32> {
        let n = self.categories.len() as u32;
        let top = PAD + text_height(SCALE) + PAD;
        let pitch = text_height(SCALE) + ROW_GAP;
        (n > 0 && top + n * pitch <= height.saturating_sub(PAD)).then_some(pitch)
    }

    /// Top and bottom rows of the bar inside a strip `height` tall.
    fn bar_rows(height: u32) -> (u32, u32) {
        let top = PAD + text_height(SCALE) + PAD;
        let bottom = height
            .saturating_sub(PAD + text_height(SCALE) / 2)
            .max(top + 1);
        (top, bottom)
    }

    /// Tick values with their labels, top (hi) to bottom (lo): five ticks
    /// when the bar is tall enough to keep labels apart, else two.
    fn ticks(&self, height: u32) -> Vec<(f32, String)> {
        let (top, bottom) = Self::bar_rows(height);
        let n = if bottom - top >= 4 * (text_height(SCALE) + 8) {
            5
        } else {
            2
        };
        let step = (self.hi - self.lo) / (n - 1) as f32;
        (0..n)
            .map(|k| {
                let v = if k == n - 1 {
                    self.lo
                } else {
                    self.hi - step * k as f32
                };
                (v, format_value(v, step))
            })
            .collect()
    }

    /// Labels beside the bar or the swatches, top to bottom.
    fn labels(&self, height: u32) -> Vec<(f32, String)> {
        if self.swatch_pitch(height).is_some() {
            self.categories
                .iter()
                .map(|&v| (v, category_label(v)))
                .collect()
        } else {
            self.ticks(height)
        }
    }

    /// Width of the strip for a grid `height` pixels tall.
    pub fn width(&self, height: u32) -> u32 {
        let labels = self
            .labels(height)
            .iter()
            .map(|(_, s)| text_width(s, SCALE))
            .max()
            .unwrap_or(0);
        let body = BAR_W + TICK + GAP + labels;
        2 * PAD + body.max(text_width(&self.name, SCALE))
    }

    /// Draws the legend into the strip whose top-left corner is `(x0, y0)`
    /// and which is `height` pixels tall.
    pub fn draw(&self, img: &mut Image, x0: u32, y0: u32, height: u32) {
        let (x0, y0) = (i64::from(x0), i64::from(y0));
        draw_text(
            img,
            x0 + i64::from(PAD),
            y0 + i64::from(PAD),
            &self.name,
            SCALE,
            INK,
        );
        if let Some(pitch) = self.swatch_pitch(height) {
            self.draw_swatches(img, x0, y0, pitch);
            return;
        }
        let (top, bottom) = Self::bar_rows(height);
        let bar_x = x0 + i64::from(PAD);
        let rows = bottom - top;
        for r in 0..=rows {
            let t = 1.0 - r as f32 / rows as f32;
            let [cr, cg, cb] = sample_srgb8(t);
            fill_rect(
                img,
                bar_x,
                y0 + i64::from(top + r),
                BAR_W,
                1,
                [cr, cg, cb, 255],
            );
        }
        // Outline.
        let (bt, bb) = (y0 + i64::from(top), y0 + i64::from(bottom));
        fill_rect(img, bar_x - 1, bt - 1, BAR_W + 2, 1, INK);
        fill_rect(img, bar_x - 1, bb + 1, BAR_W + 2, 1, INK);
        fill_rect(img, bar_x - 1, bt - 1, 1, rows + 3, INK);
        fill_rect(img, bar_x + i64::from(BAR_W), bt - 1, 1, rows + 3, INK);
        let span = self.hi - self.lo;
        for (v, label) in self.ticks(height) {
            let frac = if span > 0.0 {
                (self.hi - v) / span
            } else {
                0.5
            };
            let y = bt + (frac * rows as f32).round() as i64;
            fill_rect(img, bar_x + i64::from(BAR_W), y, TICK, 1, INK);
            let tx = bar_x + i64::from(BAR_W + TICK + GAP);
            let ty = y - i64::from(text_height(SCALE) / 2);
            draw_text(img, tx, ty, &label, SCALE, INK);
        }
    }

    /// One outlined swatch per category, lowest value at the top, each
    /// labelled with its value.
    fn draw_swatches(&self, img: &mut Image, x0: i64, y0: i64, pitch: u32) {
        let size = text_height(SCALE);
        let x = x0 + i64::from(PAD);
        let top = y0 + i64::from(PAD + text_height(SCALE) + PAD);
        for (k, &v) in self.categories.iter().enumerate() {
            let y = top + i64::from(k as u32 * pitch);
            let [r, g, b] = sample_srgb8(color_coord(v, self.lo, self.hi));
            fill_rect(img, x - 1, y - 1, BAR_W + 2, size + 2, INK);
            fill_rect(img, x, y, BAR_W, size, [r, g, b, 255]);
            let label = category_label(v);
            draw_text(
                img,
                x + i64::from(BAR_W + TICK + GAP),
                y,
                &label,
                SCALE,
                INK,
            );
        }
    }
}

/// A category's label: the whole number (`0`, never `-0`).
fn category_label(v: f32) -> String {
    format!("{:.0}", v + 0.0)
}

/// A short label for `v` on a scale whose ticks are `step` apart: fixed
/// notation with enough decimals to tell neighbouring ticks apart, or
/// scientific notation for very large or very small magnitudes.
pub(crate) fn format_value(v: f32, step: f32) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let step = step.abs();
    let tiny = v.abs() < 1e-3 && step < 1e-3;
    if v.abs() >= 1e5 || tiny {
        return format!("{v:.2e}");
    }
    let decimals = if step > 0.0 {
        (1 - step.log10().floor() as i32).clamp(0, 5) as usize
    } else {
        3
    };
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_tell_ticks_apart() {
        assert_eq!(format_value(0.25, 0.25), "0.25");
        assert_eq!(format_value(-0.05, 0.025), "-0.050");
        assert_eq!(format_value(1250.0, 250.0), "1250");
        assert_eq!(format_value(0.0, 0.1), "0");
        assert_eq!(format_value(3.0e-5, 1.0e-5), "3.00e-5");
        assert_eq!(format_value(2.5e6, 1.0e6), "2.50e6");
    }

    #[test]
    fn tick_count_follows_height_and_spans_the_range() {
        let l = Legend {
            name: "height".into(),
            lo: -1.0,
            hi: 3.0,
            categories: Vec::new(),
        };
        let tall = l.ticks(400);
        assert_eq!(tall.len(), 5);
        assert_eq!(tall[0].0, 3.0);
        assert_eq!(tall[4].0, -1.0);
        assert_eq!(l.ticks(60).len(), 2);
        assert!(l.width(400) >= 2 * PAD + BAR_W + text_width("-1.0", SCALE));
    }

    /// `l` drawn alone on white into a strip `h` tall and as wide as it asks.
    fn drawn(l: &Legend, h: u32) -> Image {
        let w = l.width(h);
        let mut img = Image {
            width: w,
            height: h,
            rgba: vec![255; (w * h * 4) as usize],
        };
        l.draw(&mut img, 0, 0, h);
        img
    }

    #[test]
    fn bar_runs_from_max_colour_at_top_to_min_at_bottom() {
        let l = Legend {
            name: "f".into(),
            lo: 0.0,
            hi: 1.0,
            categories: Vec::new(),
        };
        let h = 300;
        let img = drawn(&l, h);
        let (top, bottom) = Legend::bar_rows(h);
        let x = PAD + BAR_W / 2;
        assert_eq!(img.pixel(x, top)[..3], sample_srgb8(1.0));
        assert_eq!(img.pixel(x, bottom)[..3], sample_srgb8(0.0));
    }

    #[test]
    fn categories_get_one_labelled_swatch_each() {
        let l = Legend {
            name: "piece".into(),
            lo: 0.0,
            hi: 3.0,
            categories: vec![0.0, 1.0, 2.0, 3.0],
        };
        let h = 300;
        let pitch = l.swatch_pitch(h).expect("4 swatches fit 300 px");
        let img = drawn(&l, h);
        let top = PAD + text_height(SCALE) + PAD;
        for (k, t) in [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0].into_iter().enumerate() {
            let y = top + k as u32 * pitch + text_height(SCALE) / 2;
            assert_eq!(
                img.pixel(PAD + BAR_W / 2, y)[..3],
                sample_srgb8(t),
                "swatch {k}"
            );
        }
        // Between swatches the strip stays background, unlike a bar.
        let gap = top + pitch - ROW_GAP / 2;
        assert_eq!(img.pixel(PAD + BAR_W / 2, gap), [255; 4]);
        // Each label is drawn right of its swatch, inside the strip's width.
        let label_x = PAD + BAR_W + TICK + GAP;
        for k in 0..4 {
            let y0 = top + k * pitch;
            let inked = |xs: std::ops::Range<u32>| {
                xs.flat_map(|x| (y0..y0 + text_height(SCALE)).map(move |y| (x, y)))
                    .any(|(x, y)| img.pixel(x, y) == INK)
            };
            assert!(inked(label_x..img.width), "label {k}");
            assert!(
                !inked(img.width - PAD + 1..img.width),
                "label {k} reaches the edge"
            );
        }
        // The strip is too short for four rows: the continuous bar with ticks.
        assert!(l.swatch_pitch(100).is_none());
        assert_eq!(l.labels(100).len(), 2);
    }
}
