//! `.vti` ImageData ↔ [`Volume`].

use std::io::{self, Write};
use std::path::Path;

use super::super::saturating_product;
use super::super::text::Num;
use super::super::vtk::empty_samples;
use super::{Doc, Elem, xml_type_name};
use crate::volume::VolumeData;
use crate::{Error, Position, Result, Volume};

/// Reads a `.vti` file held in `bytes`: the volume, and the names of the
/// arrays read but not kept (`point name`, `cell name`, `field name`).
pub(crate) fn read_image(path: &Path, bytes: &[u8]) -> Result<(Volume, Vec<String>)> {
    let doc = Doc::parse(path, bytes, "ImageData")?;
    let img = doc.one(&doc.root, "ImageData")?;
    let whole: [i64; 6] = doc.numbers(img, "WholeExtent", None)?;
    let origin: [f64; 3] = doc.numbers(img, "Origin", Some([0.0; 3]))?;
    let spacing: [f64; 3] = doc.numbers(img, "Spacing", Some([1.0; 3]))?;
    let direction: [f64; 9] = doc.numbers(
        img,
        "Direction",
        Some([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]),
    )?;
    for (key, values) in [
        ("Origin", &origin[..]),
        ("Spacing", &spacing[..]),
        ("Direction", &direction[..]),
    ] {
        if values.iter().any(|v| !v.is_finite())
            || (key == "Spacing" && values.iter().any(|&v| v <= 0.0))
        {
            return Err(doc.error(
                img.at,
                format!(
                    "{key} of finite{} numbers",
                    if key == "Spacing" { ", positive" } else { "" }
                ),
                format!("{values:?}"),
            ));
        }
    }
    let dims = extent_dims(&doc, img, "WholeExtent", &whole)?;
    let n = saturating_product(dims.iter().map(|&d| d as u64));
    let mut skipped: Vec<String> = Vec::new();
    let mut note = |s: String| {
        if !skipped.contains(&s) {
            skipped.push(s);
        }
    };
    doc.skip_field_data(img, &mut note)?;
    let pieces: Vec<&Elem> = img.children_named("Piece").collect();
    if pieces.is_empty() {
        return Err(doc.error(img.at, "a <Piece> inside <ImageData>", "none"));
    }
    // The samples, filled piece by piece (directly for one whole piece).
    let mut full: Option<VolumeData> = None;
    let mut covered: Vec<bool> = Vec::new();
    let mut active_name: Option<String> = None;
    for piece in &pieces {
        let ext: [i64; 6] = doc.numbers(piece, "Extent", None)?;
        let pdims = extent_dims(&doc, piece, "Extent", &ext)?;
        if (0..3).any(|a| ext[2 * a] < whole[2 * a] || ext[2 * a + 1] > whole[2 * a + 1]) {
            return Err(doc.error(
                piece.at,
                format!("a piece Extent within the WholeExtent {whole:?}"),
                format!("{ext:?}"),
            ));
        }
        let pn = saturating_product(pdims.iter().map(|&d| d as u64));
        let cells = saturating_product(pdims.iter().map(|&d| d.saturating_sub(1).max(1) as u64));
        let mut data = None;
        if let Some(pd) = piece.child("PointData") {
            let arrays = pd
                .children_named("DataArray")
                .map(|el| doc.array(el))
                .collect::<Result<Vec<_>>>()?;
            let active = match pd.attr("Scalars") {
                Some(name) => {
                    Some(arrays.iter().position(|a| a.name == name).ok_or_else(|| {
                        doc.error(
                            pd.at,
                            format!("a DataArray named `{name}` (the PointData's Scalars)"),
                            "none",
                        )
                    })?)
                }
                None => arrays.iter().position(|a| a.comps == 1 && a.num.is_some()),
            };
            for (k, a) in arrays.iter().enumerate() {
                if Some(k) != active {
                    doc.skip(a, Some(pn.saturating_mul(a.comps)))?;
                    note(format!("point {}", a.name));
                    continue;
                }
                if a.comps != 1 {
                    return Err(Error::Unsupported {
                        path: path.into(),
                        what: format!(
                            "point scalars `{}` with {} components (at byte {}; chisel volumes \
                             hold one)",
                            a.name, a.comps, a.el.at
                        ),
                    });
                }
                if active_name.get_or_insert_with(|| a.name.clone()) != &a.name {
                    return Err(doc.error(
                        a.el.at,
                        format!(
                            "the same scalars `{}` in every piece",
                            active_name.clone().unwrap_or_default()
                        ),
                        format!("`{}`", a.name),
                    ));
                }
                data = Some(doc.volume_data(a, pn)?);
            }
        }
        if let Some(cd) = piece.child("CellData") {
            for el in cd.children_named("DataArray") {
                let a = doc.array(el)?;
                doc.skip(&a, Some(cells.saturating_mul(a.comps)))?;
                note(format!("cell {}", a.name));
            }
        }
        let data = data.ok_or_else(|| {
            doc.error(
                piece.at,
                "a one-component point DataArray (the volume's samples)",
                "none",
            )
        })?;
        if pieces.len() == 1 && pn == n {
            full = Some(data);
            break;
        }
        place(
            &doc,
            piece,
            &mut full,
            &mut covered,
            &data,
            &whole,
            &ext,
            dims,
            n,
        )?;
    }
    if let Some(missing) = covered.iter().position(|&c| !c) {
        let k = covered.iter().filter(|&&c| !c).count();
        return Err(Error::Unsupported {
            path: path.into(),
            what: format!(
                "ImageData pieces that leave {k} of {n} points of the WholeExtent uncovered \
                 (the first is point {missing})"
            ),
        });
    }
    doc.check_appended_tail()?;
    let data = full.ok_or_else(|| Error::Internal("no samples after the pieces".into()))?;
    // World = Origin + Direction · (index ⊙ Spacing), index in extent
    // coordinates; the volume's index 0 is the extent's start.
    let axes: [[f64; 3]; 3] =
        std::array::from_fn(|k| std::array::from_fn(|c| direction[3 * c + k]));
    let first: [f64; 3] = std::array::from_fn(|c| {
        origin[c]
            + (0..3)
                .map(|k| axes[k][c] * whole[2 * k] as f64 * spacing[k])
                .sum::<f64>()
    });
    let volume = Volume::new(dims, spacing, first, data)?
        .with_frame(axes, None)
        .map_err(|_| {
            doc.error(
                img.at,
                "an orthonormal Direction (sheared grids are not represented)",
                format!("{direction:?}"),
            )
        })?;
    Ok((volume, skipped))
}

/// The point counts of an extent `[x0 x1 y0 y1 z0 z1]`.
fn extent_dims(doc: &Doc, el: &Elem, key: &str, ext: &[i64; 6]) -> Result<[usize; 3]> {
    let mut dims = [0usize; 3];
    for a in 0..3 {
        let d = ext[2 * a + 1]
            .checked_sub(ext[2 * a])
            .and_then(|d| d.checked_add(1))
            .and_then(|d| usize::try_from(d).ok())
            .filter(|&d| d >= 1);
        dims[a] = d.ok_or_else(|| {
            doc.error(
                el.at,
                format!("{key} with x1 ≥ x0, y1 ≥ y0, z1 ≥ z0"),
                format!("{ext:?}"),
            )
        })?;
    }
    dims.iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| {
            doc.error(
                el.at,
                format!("a {key} whose point count fits"),
                format!("{ext:?}"),
            )
        })?;
    Ok(dims)
}

/// Copies one piece's samples into the whole volume (allocated on the
/// first piece), marking the points it covers.
#[allow(clippy::too_many_arguments)]
fn place(
    doc: &Doc,
    piece: &Elem,
    full: &mut Option<VolumeData>,
    covered: &mut Vec<bool>,
    data: &VolumeData,
    whole: &[i64; 6],
    ext: &[i64; 6],
    dims: [usize; 3],
    n: u64,
) -> Result<()> {
    if full.is_none() {
        let num = num_of(data);
        let at = Position::Byte(piece.at as u64);
        super::super::check_budget(
            doc.path,
            at.clone(),
            "the whole image",
            n.saturating_mul(num.size() as u64 + 1),
        )?;
        let n = n as usize;
        let mut d = empty_samples(doc.path, num, n, "the whole image")?;
        macro_rules! zero {
            ($($v:ident),*) => { match &mut d { $(VolumeData::$v(v) => v.resize(n, Default::default()),)* } };
        }
        zero!(U8, I8, U16, I16, U32, I32, F32, F64);
        covered
            .try_reserve_exact(n)
            .map_err(|_| Error::HostMemory {
                what: format!("{}: the piece coverage", doc.path.display()),
                bytes: n as u64,
            })?;
        covered.resize(n, false);
        *full = Some(d);
    }
    let Some(dst) = full.as_mut() else {
        return Ok(());
    };
    let [px, py, pz] = [
        (ext[1] - ext[0] + 1) as usize,
        (ext[3] - ext[2] + 1) as usize,
        (ext[5] - ext[4] + 1) as usize,
    ];
    let [ox, oy, oz] = [
        (ext[0] - whole[0]) as usize,
        (ext[2] - whole[2]) as usize,
        (ext[4] - whole[4]) as usize,
    ];
    macro_rules! copy {
        ($($v:ident),*) => {
            match (dst, data) {
                $((VolumeData::$v(d), VolumeData::$v(s)) => {
                    for z in 0..pz {
                        for y in 0..py {
                            let to = ox + dims[0] * (oy + y + dims[1] * (oz + z));
                            let from = px * (y + py * z);
                            d[to..to + px].copy_from_slice(&s[from..from + px]);
                            covered[to..to + px].iter_mut().for_each(|c| *c = true);
                        }
                    }
                })*
                _ => {
                    return Err(doc.error(
                        piece.at,
                        "the same scalar type in every piece",
                        format!("{:?}", data.scalar_type()),
                    ))
                }
            }
        };
    }
    copy!(U8, I8, U16, I16, U32, I32, F32, F64);
    Ok(())
}

/// Writes `v` as a `.vti` file: little-endian, `header_type="UInt64"`,
/// one appended raw array `scalars` in the volume's own type, `Origin`,
/// `Spacing` and `Direction` (columns = `v.axes`). `v.space` is not
/// stored (a `.vti` has no anatomical frame): world coordinates are
/// written as they are.
pub(crate) fn write_image(w: &mut dyn Write, v: &Volume) -> io::Result<()> {
    let [nx, ny, nz] = v.dims;
    let num = num_of(&v.data);
    let ext = format!(
        "0 {} 0 {} 0 {}",
        nx.saturating_sub(1),
        ny.saturating_sub(1),
        nz.saturating_sub(1)
    );
    let f = |x: &[f64]| {
        x.iter()
            .map(|x| format!("{x:?}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let direction: Vec<f64> = (0..9).map(|i| v.axes[i % 3][i / 3]).collect();
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(
        w,
        "  <ImageData WholeExtent=\"{ext}\" Origin=\"{}\" Spacing=\"{}\" Direction=\"{}\">",
        f(&v.origin),
        f(&v.spacing),
        f(&direction)
    )?;
    writeln!(w, "    <Piece Extent=\"{ext}\">")?;
    writeln!(w, "      <PointData Scalars=\"scalars\">")?;
    writeln!(
        w,
        "        <DataArray type=\"{}\" Name=\"scalars\" format=\"appended\" offset=\"0\"/>",
        xml_type_name(num)
    )?;
    writeln!(w, "      </PointData>")?;
    writeln!(w, "      <CellData>\n      </CellData>")?;
    writeln!(w, "    </Piece>\n  </ImageData>")?;
    write!(w, "  <AppendedData encoding=\"raw\">\n   _")?;
    w.write_all(&((v.len() * num.size()) as u64).to_le_bytes())?;
    super::super::raw::write_le(w, &v.data)?;
    writeln!(w, "\n  </AppendedData>\n</VTKFile>")
}

/// The file type of `data`'s samples.
fn num_of(data: &VolumeData) -> Num {
    match data {
        VolumeData::U8(_) => Num::U8,
        VolumeData::I8(_) => Num::I8,
        VolumeData::U16(_) => Num::U16,
        VolumeData::I16(_) => Num::I16,
        VolumeData::U32(_) => Num::U32,
        VolumeData::I32(_) => Num::I32,
        VolumeData::F32(_) => Num::F32,
        VolumeData::F64(_) => Num::F64,
    }
}
