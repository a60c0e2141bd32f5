//! A folder of 2D slices (PNG, 8 or 16-bit grayscale; TIFF, any grayscale
//! type [`super::tiff`] reads) read as a volume: one slice per z, in
//! natural file-name order (`slice2` before `slice10`). Files with other
//! extensions are ignored; every slice must have the first slice's size
//! and type. A single PNG reads as a volume of depth 1; a single TIFF with
//! all its pages (a multi-page TIFF is a 3D volume). A folder of DICOM
//! files is one series, read by [`super::dicom`].

use super::{ReadError, ReadOptions, ScalarType, Volume, check_dims, finish, invalid, io_error};
use crate::field::Values;
use std::path::{Path, PathBuf};

fn is_slice(p: &Path) -> bool {
    let ext = p
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    matches!(ext.as_str(), "png" | "tif" | "tiff") && p.is_file()
}

/// Reads a folder of slices.
pub fn read(dir: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let entries = std::fs::read_dir(dir).map_err(|e| io_error(dir, e))?;
    let mut files: Vec<PathBuf> = Vec::new();
    let mut dicom: Vec<PathBuf> = Vec::new();
    for e in entries {
        let p = e.map_err(|e| io_error(dir, e))?.path();
        if is_slice(&p) {
            files.push(p);
        } else if super::dicom::is_dicom_file(&p) {
            dicom.push(p);
        }
    }
    if !dicom.is_empty() {
        if !files.is_empty() {
            return Err(invalid(
                dir,
                format!(
                    "holds both DICOM files ({}) and PNG/TIFF slices ({}): give a folder of one kind",
                    dicom.len(),
                    files.len()
                ),
            ));
        }
        dicom.sort_by(|a, b| super::natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
        return super::dicom::read_series(dir, &dicom, opts);
    }
    if files.is_empty() {
        return Err(invalid(
            dir,
            "is a directory without PNG or TIFF slices or DICOM files (give a volume file, or a folder of slices)",
        ));
    }
    files.sort_by(|a, b| {
        let name = |p: &PathBuf| {
            p.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        super::natural_cmp(&name(a), &name(b))
    });
    read_files(dir, &files, opts)
}

/// Reads one image: a PNG as a volume of depth 1, a TIFF with all its
/// pages (one per z: a multi-page TIFF is a 3D volume).
pub fn read_single(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    if !is_tiff(path) {
        return read_files(path, &[path.to_owned()], opts);
    }
    let pages = super::tiff::read(path, |dims, ty| check_dims(path, dims, ty, opts).map(drop))?;
    let format = match pages.dims[2] {
        1 => "TIFF (1 page)".to_owned(),
        n => format!("TIFF ({n} pages)"),
    };
    finish(
        path,
        pages.dims,
        [1.0; 3],
        pages.values,
        pages.scalar_type,
        format,
        opts,
        Vec::new(),
    )
}

fn is_tiff(p: &Path) -> bool {
    let ext = p
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    matches!(ext.as_str(), "tif" | "tiff")
}

/// One slice: its width, height, values and type.
fn slice(p: &Path) -> Result<(usize, usize, Values, ScalarType), ReadError> {
    if is_tiff(p) {
        let pages = super::tiff::read(p, |_, _| Ok(()))?;
        if pages.dims[2] != 1 {
            return Err(invalid(
                p,
                format!(
                    "slice has {} pages: a folder of slices takes one 2D image per file \
                     (open a multi-page TIFF as a file)",
                    pages.dims[2]
                ),
            ));
        }
        return Ok((
            pages.dims[0],
            pages.dims[1],
            pages.values,
            pages.scalar_type,
        ));
    }
    let img = image::ImageReader::open(p)
        .map_err(|e| io_error(p, e))?
        .with_guessed_format()
        .map_err(|e| io_error(p, e))?
        .decode()
        .map_err(|e| invalid(p, format!("cannot decode image: {e}")))?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    match img {
        image::DynamicImage::ImageLuma8(b) => Ok((w, h, Values::U8(b.into_raw()), ScalarType::U8)),
        image::DynamicImage::ImageLuma16(b) => {
            Ok((w, h, Values::U16(b.into_raw()), ScalarType::U16))
        }
        other => Err(invalid(
            p,
            format!("slice is {:?}, not 8 or 16-bit grayscale", other.color()),
        )),
    }
}

fn read_files(path: &Path, files: &[PathBuf], opts: &ReadOptions) -> Result<Volume, ReadError> {
    // Size and type from the first slice, then one allocation for all.
    let (w, h, first, ty) = slice(&files[0])?;
    let dims = [w, h, files.len()];
    let n = check_dims(path, dims, ty, opts)?;
    let mut values = first;
    crate::with_values!(&mut values, v => v.reserve(n.saturating_sub(v.len())));
    for p in &files[1..] {
        let (sw, sh, more, sty) = slice(p)?;
        if (sw, sh) != (w, h) {
            return Err(invalid(
                p,
                format!("slice is {sw}x{sh} but the first slice is {w}x{h}"),
            ));
        }
        if sty != ty {
            return Err(invalid(
                p,
                format!(
                    "slice holds {} but the first slice holds {}",
                    sty.name(),
                    ty.name()
                ),
            ));
        }
        match (&mut values, more) {
            (Values::U8(v), Values::U8(m)) => v.extend_from_slice(&m),
            (Values::I8(v), Values::I8(m)) => v.extend_from_slice(&m),
            (Values::U16(v), Values::U16(m)) => v.extend_from_slice(&m),
            (Values::I16(v), Values::I16(m)) => v.extend_from_slice(&m),
            (Values::U32(v), Values::U32(m)) => v.extend_from_slice(&m),
            (Values::I32(v), Values::I32(m)) => v.extend_from_slice(&m),
            (Values::F32(v), Values::F32(m)) => v.extend_from_slice(&m),
            (Values::F64(v), Values::F64(m)) => v.extend_from_slice(&m),
            _ => return Err(invalid(p, "slice type differs from the first slice's")),
        }
    }
    let format = if files.len() == 1 && files[0] == path {
        "image (1 slice)".to_owned()
    } else {
        format!("image stack ({} slices)", files.len())
    };
    finish(path, dims, [1.0; 3], values, ty, format, opts, Vec::new())
}
