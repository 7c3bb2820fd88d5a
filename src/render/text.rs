//! CPU drawing on an [`Image`]: filled rectangles and 8×8 bitmap text
//! (`font8x8`, public-domain glyphs), scaled by an integer factor. Everything
//! clips to the image, so callers may draw partly outside it.

use super::Image;

/// Glyph cell edge in font pixels.
const GLYPH: u32 = 8;

/// Width in pixels of `text` drawn at `scale` (one glyph cell per char).
pub(crate) fn text_width(text: &str, scale: u32) -> u32 {
    u32::try_from(text.chars().count())
        .unwrap_or(u32::MAX)
        .saturating_mul(GLYPH * scale)
}

/// Height in pixels of one line of text at `scale`.
pub(crate) fn text_height(scale: u32) -> u32 {
    GLYPH * scale
}

/// Fills the rectangle `[x, x + w) × [y, y + h)` with `rgba` (clipped).
pub(crate) fn fill_rect(img: &mut Image, x: i64, y: i64, w: u32, h: u32, rgba: [u8; 4]) {
    let x0 = x.clamp(0, i64::from(img.width));
    let y0 = y.clamp(0, i64::from(img.height));
    let x1 = (x + i64::from(w)).clamp(0, i64::from(img.width));
    let y1 = (y + i64::from(h)).clamp(0, i64::from(img.height));
    for yy in y0..y1 {
        for xx in x0..x1 {
            let i = ((yy as usize) * img.width as usize + xx as usize) * 4;
            img.rgba[i..i + 4].copy_from_slice(&rgba);
        }
    }
}

/// Draws `text` with its top-left corner at `(x, y)`, each font pixel a
/// `scale`×`scale` block of `rgba`. Characters outside ASCII draw as `?`.
pub(crate) fn draw_text(img: &mut Image, x: i64, y: i64, text: &str, scale: u32, rgba: [u8; 4]) {
    let step = i64::from(GLYPH * scale);
    for (k, ch) in text.chars().enumerate() {
        let code = if ch.is_ascii() {
            ch as usize
        } else {
            '?' as usize
        };
        let glyph = font8x8::legacy::BASIC_LEGACY[code];
        let gx = x + k as i64 * step;
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..GLYPH {
                // Bit 0 is the leftmost pixel of the row.
                if bits >> col & 1 == 1 {
                    fill_rect(
                        img,
                        gx + i64::from(col * scale),
                        y + row as i64 * i64::from(scale),
                        scale,
                        scale,
                        rgba,
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blank(w: u32, h: u32) -> Image {
        Image {
            width: w,
            height: h,
            rgba: vec![255; (w * h * 4) as usize],
        }
    }

    #[test]
    fn glyph_pixels_land_inside_its_cell() {
        let mut img = blank(40, 20);
        draw_text(&mut img, 4, 2, "1", 2, [0, 0, 0, 255]);
        let mut dark = 0;
        for y in 0..20u32 {
            for x in 0..40u32 {
                if img.pixel(x, y)[0] == 0 {
                    dark += 1;
                    assert!((4..20).contains(&x) && (2..18).contains(&y), "({x}, {y})");
                }
            }
        }
        // '1' in font8x8 has 19 set bits; each becomes a 2×2 block.
        assert_eq!(dark, 19 * 4);
        assert_eq!(text_width("abc", 2), 48);
    }

    #[test]
    fn drawing_off_the_image_is_clipped() {
        let mut img = blank(10, 10);
        draw_text(&mut img, -30, -5, "Wide text", 3, [0, 0, 0, 255]);
        fill_rect(&mut img, 8, 8, 100, 100, [1, 2, 3, 255]);
        assert_eq!(img.pixel(9, 9), [1, 2, 3, 255]);
        assert_eq!(img.rgba.len(), 400);
    }
}
