//! Headless previews (SPEC §0.6): a mesh drawn by a wgpu render pipeline
//! (`shaders/mesh.wgsl`, `shaders/wireframe.wgsl`) into an offscreen 4×
//! multisampled sRGB texture, read back and written as PNG.
//!
//! * **Shading**: Lambert + Blinn–Phong from a key light above-left of the
//!   camera, with smooth per-vertex normals computed on the GPU by the
//!   `vertex_normals` kernel and bound straight into the vertex stage.
//!   Two-sided, no culling: a mesh and its [`TriMesh::flip_winding`] copy
//!   give the same image, so inward-wound scans (fran_cut, bunny) look right.
//! * **Wireframe** (optional): the unique edges as dark lines, pulled a few
//!   pixels of depth toward the camera so they sit on the surface.
//! * **Scalars** (optional): a per-vertex [`ScalarField`](crate::mesh::ScalarField)
//!   through viridis, interpolated per fragment, over the field's finite
//!   min..max or a user range (values outside clamp; non-finite values draw
//!   dark grey), with a legend strip at the right: colour bar, field name and
//!   tick values (8×8 bitmap font at 2×), or, for 2 to 16 whole-number
//!   values without a user range, one labelled swatch per value (lowest at
//!   the top) when they fit the strip's height.
//! * **Camera**: orthographic, framing the bounding sphere of the drawn
//!   vertices (box centre, largest distance) with an 8 % margin; one sphere
//!   for all views and panels, so sizes compare.
//!
//! # View convention
//! +y is up. [`View::Front`] looks from +z toward −z (x to the right, y up),
//! [`View::Back`] from −z, [`View::Right`] from +x (the right-hand side of
//! the front view), [`View::Left`] from −x, [`View::Top`] from +y down (the
//! front at the image bottom), [`View::Bottom`] from −y (front at the top),
//! [`View::Iso`] from the front-right-top diagonal (+x +y +z), y up.
//!
//! With [`Facing::Auto`] (the default) the frame is turned about +y so that
//! `front` looks at the bulging side of an *open* surface (a scan whose
//! vector area is at least a quarter of its area, e.g. a face): fran_cut's
//! face looks toward ≈ (+0.81, 0, −0.59), and that is where its `front`
//! camera sits (its scan axis is y, so the face is upright, chin at −y). Closed or nearly closed meshes (footbones, the bunny, whose
//! holes are small) keep the fixed axes above. [`Facing::Axes`] always uses
//! the fixed axes; [`Facing::Anatomical`] takes `up` and `front` from the
//! caller (a CT volume's patient axes, e.g. headsq: up −z, front −y).
//!
//! # Layout
//! Each view is a `width`×`height` cell: its name (with the panel caption)
//! in a band of [`CAPTION_HEIGHT`] pixels at the top, the mesh framed in
//! the `width`×(`height` − band) area below (views under 4 bands tall draw
//! the caption over the mesh and frame the whole cell). [`render_image`]
//! lays the views out as a grid of ⌈√n⌉ columns, row by row;
//! [`render_panels`] puts panels side by side (one column each) and views
//! in rows. An optional title adds a band of
//! [`TITLE_HEIGHT`] pixels on top; a colour map adds the legend strip at the
//! right. Without both the image is exactly the grid.

mod camera;
mod colormap;
mod legend;
mod pipeline;
mod text;

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use glam::Vec3;

use crate::mesh::TriMesh;
use crate::{Error, Gpu, Result};

use camera::{Frame, bounding_sphere, view_camera};
use legend::{INK, Legend, MAX_CATEGORIES};
use pipeline::{BACKGROUND, CellDraw, PanelGeometry, render_grid};
use text::{draw_text, fill_rect, text_height, text_width};

/// Height in pixels of the title band (only when a title is given).
pub const TITLE_HEIGHT: u32 = 32;
/// Height in pixels of the caption band at the top of each view, kept
/// free of the mesh when the view is at least 4 bands tall (smaller views
/// draw the caption over the mesh instead).
pub const CAPTION_HEIGHT: u32 = 28;
/// Text scale of captions and title (8×8 glyphs drawn 16×16).
const TEXT_SCALE: u32 = 2;
/// Inset of a caption from its cell's top-left corner, pixels.
const CAPTION_INSET: u32 = 6;

/// A camera direction; see the module docs for the convention.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum View {
    Front,
    Back,
    Left,
    Right,
    Top,
    Bottom,
    Iso,
}

impl View {
    /// Every view, in declaration order.
    pub const ALL: &'static [View] = &[
        View::Front,
        View::Back,
        View::Left,
        View::Right,
        View::Top,
        View::Bottom,
        View::Iso,
    ];

    /// The lower-case name (`front`, …, `iso`), as parsed and captioned.
    pub fn name(self) -> &'static str {
        match self {
            View::Front => "front",
            View::Back => "back",
            View::Left => "left",
            View::Right => "right",
            View::Top => "top",
            View::Bottom => "bottom",
            View::Iso => "iso",
        }
    }
}

impl fmt::Display for View {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for View {
    type Err = Error;

    /// Parses a lower-case view name; `side` means [`View::Right`].
    fn from_str(s: &str) -> Result<Self> {
        if s == "side" {
            return Ok(View::Right);
        }
        View::ALL
            .iter()
            .copied()
            .find(|v| v.name() == s)
            .ok_or_else(|| {
                Error::unknown(
                    "view",
                    s,
                    View::ALL
                        .iter()
                        .map(|v| v.name())
                        .chain(std::iter::once("side")),
                )
            })
    }
}

/// How view names map to world directions (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Facing {
    /// +y up; `front` faces the bulging side of an open surface, else +z.
    #[default]
    Auto,
    /// +y up, `front` looks from +z, always.
    Axes,
    /// Given world directions: `up` is image-up in the side views, `front`
    /// points from the object toward the front camera (made orthogonal to
    /// `up`). Both non-zero and not parallel, else the fixed axes are used.
    Anatomical { up: Vec3, front: Vec3 },
}

/// What to draw and how big.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Pixels per view, horizontally (≥ 1).
    pub width: u32,
    /// Pixels per view, vertically (≥ 1).
    pub height: u32,
    /// Views to draw, in grid order (at least one).
    pub views: Vec<View>,
    /// Overlay the unique edges as lines.
    pub wireframe: bool,
    /// Name of the per-vertex scalar field to colour by.
    pub scalars: Option<String>,
    /// Colour-map range `(lo, hi)`, `lo < hi`; `None` = the field's min..max.
    pub scalar_range: Option<(f32, f32)>,
    /// Title drawn in a band above the views.
    pub title: Option<String>,
    /// How view names map to directions.
    pub facing: Facing,
}

impl Default for RenderOptions {
    /// 512×512 pixels, the `front` view, shaded grey, no title.
    fn default() -> Self {
        RenderOptions {
            width: 512,
            height: 512,
            views: vec![View::Front],
            wireframe: false,
            scalars: None,
            scalar_range: None,
            title: None,
            facing: Facing::Auto,
        }
    }
}

/// An 8-bit sRGB RGBA image, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// `width · height · 4` bytes.
    pub rgba: Vec<u8>,
}

impl Image {
    /// The pixel at column `x`, row `y` (0 = top). Panics out of bounds.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// Encodes the image as PNG (8-bit RGBA).
    pub fn to_png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        let wrap = |e: png::EncodingError| Error::Internal(format!("PNG encoding: {e}"));
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            let mut writer = enc.write_header().map_err(wrap)?;
            writer.write_image_data(&self.rgba).map_err(wrap)?;
            writer.finish().map_err(wrap)?;
        }
        Ok(out)
    }

    /// Writes the image as PNG to `path`, atomically (temp file + rename);
    /// a name not ending in `.png` is refused.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        crate::foundation::fs::check_png_output(path)?;
        crate::foundation::fs::write_atomic(path, &self.to_png()?)
    }

    /// `images` one below the other, left-aligned on the background.
    pub fn stack(images: &[Image]) -> Image {
        let width = images.iter().map(|i| i.width).max().unwrap_or(0);
        let height = images.iter().map(|i| i.height).sum();
        let mut out = Image::blank(width, height);
        let mut y = 0;
        for i in images {
            out.blit(i, 0, y);
            y += i.height;
        }
        out
    }

    fn blank(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            rgba: BACKGROUND.repeat(width as usize * height as usize),
        }
    }

    /// Copies `src` into `self` with its top-left corner at `(x, y)`.
    fn blit(&mut self, src: &Image, x: u32, y: u32) {
        let row = src.width as usize * 4;
        for r in 0..src.height as usize {
            let d = ((y as usize + r) * self.width as usize + x as usize) * 4;
            self.rgba[d..d + row].copy_from_slice(&src.rgba[r * row..(r + 1) * row]);
        }
    }
}

/// One mesh of a side-by-side comparison ([`render_panels`]).
#[derive(Debug, Clone)]
pub struct Panel<'a> {
    pub mesh: &'a TriMesh,
    /// Caption prefix (e.g. `before`); empty for none.
    pub caption: String,
    /// Scalar field to colour by; `None` falls back to
    /// [`RenderOptions::scalars`].
    pub scalars: Option<String>,
}

/// Renders `mesh` as described by `opts` (views in a grid).
pub fn render_image(gpu: &Gpu, mesh: &TriMesh, opts: &RenderOptions) -> Result<Image> {
    render_panels(
        gpu,
        &[Panel {
            mesh,
            caption: String::new(),
            scalars: None,
        }],
        opts,
    )
}

/// Renders `mesh` and writes the PNG to `path` atomically.
pub fn render_png(gpu: &Gpu, mesh: &TriMesh, opts: &RenderOptions, path: &Path) -> Result<()> {
    render_image(gpu, mesh, opts)?.save_png(path)
}

/// Renders `panels` side by side (one column each, views in rows), sharing
/// ONE camera framing (the bounding sphere of all panels) and ONE colour
/// range (the union of the panels' fields, or the user range), so
/// before/after pictures compare honestly. A single panel lays its views out
/// as a ⌈√n⌉-column grid instead.
///
/// Errors: no panels or views or a mesh without triangles
/// ([`Error::Mismatch`]), a zero size or an empty or non-finite range
/// ([`Error::InvalidParameter`]), bad indices ([`Error::InvalidData`]), an
/// unknown scalar field ([`Error::Unknown`], listing the available ones), a
/// grid larger than the adapter's texture limit ([`Error::Limit`]). GPU failures come back as the
/// GPU error variants.
pub fn render_panels(gpu: &Gpu, panels: &[Panel<'_>], opts: &RenderOptions) -> Result<Image> {
    if panels.is_empty() {
        return Err(Error::empty("render: meshes"));
    }
    if opts.views.is_empty() {
        return Err(Error::empty("render: views"));
    }
    if opts.width == 0 || opts.height == 0 {
        return Err(Error::param(
            "render: view size",
            format!("{}×{}", opts.width, opts.height),
            "must be at least 1×1",
        ));
    }
    for p in panels {
        p.mesh.validate()?;
        if p.mesh.triangles.is_empty() {
            return Err(Error::empty(format!(
                "render: triangles of mesh{}",
                caption_suffix(&p.caption)
            )));
        }
    }
    let fields = panels
        .iter()
        .map(|p| scalar_values(p, opts))
        .collect::<Result<Vec<_>>>()?;
    let legend = colour_legend(&fields, opts.scalar_range)?;
    let geometry: Vec<PanelGeometry<'_>> = panels
        .iter()
        .zip(&fields)
        .map(|(p, f)| PanelGeometry {
            mesh: p.mesh,
            color_coords: match (f, &legend) {
                (Some((_, values)), Some(l)) => Some(color_coords(values, l.lo, l.hi)),
                _ => None,
            },
        })
        .collect();

    let meshes: Vec<&TriMesh> = panels.iter().map(|p| p.mesh).collect();
    let frame = Frame::for_meshes(&meshes, opts.facing);
    let sphere =
        bounding_sphere(&meshes).ok_or_else(|| Error::empty("render: triangles to frame"))?;
    let (cols, rows) = if panels.len() == 1 {
        let n = opts.views.len();
        let cols = n.isqrt() + usize::from(n.isqrt().pow(2) < n);
        (cols, n.div_ceil(cols))
    } else {
        (panels.len(), opts.views.len())
    };
    let (w, h) = (opts.width, opts.height);
    let band = if h >= 4 * CAPTION_HEIGHT {
        CAPTION_HEIGHT
    } else {
        0
    };
    let grid_w = dim(cols, w)?;
    let grid_h = dim(rows, h)?;
    let mut cells = Vec::new();
    let mut captions = Vec::new();
    for (vi, &view) in opts.views.iter().enumerate() {
        for (pi, p) in panels.iter().enumerate() {
            let (c, r) = if panels.len() == 1 {
                (vi % cols, vi / cols)
            } else {
                (pi, vi)
            };
            let (x, y) = (c as u32 * w, r as u32 * h);
            cells.push(CellDraw {
                panel: pi,
                camera: view_camera(&frame, sphere, view, w, h - band),
                x,
                y: y + band,
            });
            let caption = if p.caption.is_empty() {
                view.name().to_string()
            } else {
                format!("{} - {}", p.caption, view.name())
            };
            captions.push((x, y, caption));
        }
    }
    let grid = render_grid(
        gpu,
        &geometry,
        &cells,
        (w, h - band),
        (grid_w, grid_h),
        opts.wireframe,
    )?;

    let title_h = if opts.title.is_some() {
        TITLE_HEIGHT
    } else {
        0
    };
    let legend_w = legend.as_ref().map_or(0, |l| l.width(grid_h));
    let mut img = Image::blank(
        grid_w.saturating_add(legend_w),
        grid_h.saturating_add(title_h),
    );
    img.blit(&grid, 0, title_h);
    for (x, y, caption) in &captions {
        let (x, y) = (x + CAPTION_INSET, y + title_h + CAPTION_INSET);
        draw_text(&mut img, x.into(), y.into(), caption, TEXT_SCALE, INK);
    }
    if let Some(title) = &opts.title {
        let (title, scale) = fit_title(title, img.width.saturating_sub(16));
        let y = (TITLE_HEIGHT - text_height(scale)) / 2;
        draw_text(&mut img, 8, y.into(), &title, scale, INK);
        let width = img.width;
        fill_rect(
            &mut img,
            0,
            i64::from(TITLE_HEIGHT) - 1,
            width,
            1,
            [200, 200, 200, 255],
        );
    }
    if let Some(l) = &legend {
        l.draw(&mut img, grid_w, title_h, grid_h);
    }
    Ok(img)
}

/// The title and its text scale for `room` pixels: the usual scale when it
/// fits, else half that, else cut short with `...` at half scale.
fn fit_title(title: &str, room: u32) -> (String, u32) {
    for scale in [TEXT_SCALE, 1] {
        if text_width(title, scale) <= room {
            return (title.to_string(), scale);
        }
    }
    let glyph = text_width("x", 1).max(1);
    let keep = (room / glyph).saturating_sub(3) as usize;
    (
        format!("{}...", title.chars().take(keep).collect::<String>()),
        1,
    )
}

/// `n` cells of `px` pixels, as a texture dimension.
fn dim(n: usize, px: u32) -> Result<u32> {
    u32::try_from(n)
        .ok()
        .and_then(|n| n.checked_mul(px))
        .ok_or_else(|| {
            Error::limit(
                format!("render: pixels of {n} views of {px}"),
                u64::MAX,
                u32::MAX,
            )
        })
}

fn caption_suffix(caption: &str) -> String {
    if caption.is_empty() {
        String::new()
    } else {
        format!(" `{caption}`")
    }
}

/// The scalar field a panel is coloured by, as `(name, values)`, or `None`
/// for plain shading. An unknown name is an error listing the fields.
fn scalar_values<'a>(
    p: &'a Panel<'a>,
    opts: &'a RenderOptions,
) -> Result<Option<(&'a str, &'a [f32])>> {
    let Some(name) = p.scalars.as_deref().or(opts.scalars.as_deref()) else {
        return Ok(None);
    };
    match p.mesh.scalar(name) {
        Some(f) => Ok(Some((name, &f.values))),
        None => {
            let available: Vec<&str> = p.mesh.scalars.iter().map(|s| s.name.as_str()).collect();
            Err(Error::unknown("scalar field", name, available)
                .within(format!("render: mesh{}", caption_suffix(&p.caption))))
        }
    }
}

/// The legend shared by all coloured panels: the names (joined when they
/// differ) and the user range or the union of the finite values' ranges.
fn colour_legend(
    fields: &[Option<(&str, &[f32])>],
    user: Option<(f32, f32)>,
) -> Result<Option<Legend>> {
    let used: Vec<&(&str, &[f32])> = fields.iter().flatten().collect();
    if used.is_empty() {
        return Ok(None);
    }
    let mut names: Vec<&str> = Vec::new();
    for (n, _) in &used {
        if !names.contains(n) {
            names.push(n);
        }
    }
    let (lo, hi) = match user {
        Some((lo, hi)) => {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(Error::param(
                    "render: scalar range",
                    format!("({lo}, {hi})"),
                    "must be finite with lo < hi",
                ));
            }
            (lo, hi)
        }
        None => used
            .iter()
            .flat_map(|(_, v)| v.iter().copied())
            .filter(|v| v.is_finite())
            .fold(None, |acc: Option<(f32, f32)>, v| {
                Some(acc.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
            })
            .unwrap_or((0.0, 0.0)),
    };
    Ok(Some(Legend {
        name: names.join(" / "),
        lo,
        hi,
        categories: if user.is_none() {
            categories(used.iter().flat_map(|(_, v)| v.iter().copied()))
        } else {
            Vec::new()
        },
    }))
}

/// The distinct values (ascending) when there are 2 to [`MAX_CATEGORIES`]
/// of them, all whole numbers (ids, labels, depths); else none. Non-finite
/// values are skipped, as they are drawn grey.
fn categories(values: impl Iterator<Item = f32>) -> Vec<f32> {
    let mut seen: Vec<f32> = Vec::new();
    for v in values.filter(|v| v.is_finite()) {
        if v.fract() != 0.0 || v.abs() > 1e6 {
            return Vec::new();
        }
        if !seen.contains(&v) {
            if seen.len() == MAX_CATEGORIES {
                return Vec::new();
            }
            seen.push(v);
        }
    }
    if seen.len() < 2 {
        return Vec::new();
    }
    seen.sort_by(f32::total_cmp);
    seen
}

/// Per-vertex colour-map coordinates: (v − lo)/(hi − lo) clamped to [0, 1];
/// 0.5 for a constant field; −1 (drawn grey) for non-finite values.
fn color_coords(values: &[f32], lo: f32, hi: f32) -> Vec<f32> {
    values.iter().map(|&v| color_coord(v, lo, hi)).collect()
}

/// One value's colour-map coordinate (see [`color_coords`]).
pub(crate) fn color_coord(v: f32, lo: f32, hi: f32) -> f32 {
    if !v.is_finite() {
        -1.0
    } else if hi > lo {
        ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        0.5
    }
}

/// All undirected edges `[lo, hi]` of `triangles`, sorted, one entry per
/// triangle side (an interior manifold edge appears twice).
pub(crate) fn undirected_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges
}

#[cfg(test)]
mod tests {
    use super::{MAX_CATEGORIES, categories, fit_title};

    #[test]
    fn titles_shrink_then_shorten_to_fit() {
        assert_eq!(fit_title("abc", 48), ("abc".to_string(), 2));
        assert_eq!(fit_title("abcdef", 48), ("abcdef".to_string(), 1));
        // 48 px hold 6 glyphs at scale 1: 3 kept and the ellipsis.
        assert_eq!(fit_title("abcdefg", 48), ("abc...".to_string(), 1));
    }

    #[test]
    fn a_few_whole_numbers_are_categories() {
        let ids = [2.0, 0.0, 1.0, 2.0, f32::NAN, 0.0];
        assert_eq!(categories(ids.into_iter()), vec![0.0, 1.0, 2.0]);
        // Fractions, a single value, or too many values: a continuous bar.
        assert!(categories([0.0, 0.5].into_iter()).is_empty());
        assert!(categories([3.0, 3.0].into_iter()).is_empty());
        let many = (0..=MAX_CATEGORIES).map(|k| k as f32);
        assert!(categories(many).is_empty());
        assert_eq!(
            categories((0..MAX_CATEGORIES).map(|k| k as f32)).len(),
            MAX_CATEGORIES
        );
    }
}
