//! A folder of 2D slices (PNG or TIFF, 8 or 16-bit grayscale) read as a
//! volume: one slice per z, in natural file-name order (`slice2` before
//! `slice10`). Files with other extensions are ignored; every slice must
//! have the first slice's size and bit depth. A single image file reads as a
//! volume of depth 1.

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
    for e in entries {
        let p = e.map_err(|e| io_error(dir, e))?.path();
        if is_slice(&p) {
            files.push(p);
        }
    }
    if files.is_empty() {
        return Err(invalid(
            dir,
            "is a directory without PNG or TIFF slices (give a volume file, or a folder of slices)",
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

/// Reads one image as a volume of depth 1.
pub fn read_single(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    read_files(path, &[path.to_owned()], opts)
}

fn open(p: &Path) -> Result<image::DynamicImage, ReadError> {
    image::ImageReader::open(p)
        .map_err(|e| io_error(p, e))?
        .with_guessed_format()
        .map_err(|e| io_error(p, e))?
        .decode()
        .map_err(|e| invalid(p, format!("cannot decode image: {e}")))
}

fn read_files(path: &Path, files: &[PathBuf], opts: &ReadOptions) -> Result<Volume, ReadError> {
    // Size and depth from the first slice, then one allocation for all.
    let first = open(&files[0])?;
    let (w, h) = (first.width() as usize, first.height() as usize);
    let ty = depth(&files[0], &first)?;
    let dims = [w, h, files.len()];
    let n = check_dims(path, dims, ty, opts)?;
    let mut values = match ty {
        ScalarType::U8 => Values::U8(Vec::with_capacity(n)),
        _ => Values::U16(Vec::with_capacity(n)),
    };
    let mut push = |p: &Path, img: image::DynamicImage| -> Result<(), ReadError> {
        if (img.width() as usize, img.height() as usize) != (w, h) {
            return Err(invalid(
                p,
                format!(
                    "slice is {}x{} but the first slice is {w}x{h}",
                    img.width(),
                    img.height()
                ),
            ));
        }
        if depth(p, &img)? != ty {
            return Err(invalid(
                p,
                format!(
                    "slice bit depth differs from the first slice's ({})",
                    ty.name()
                ),
            ));
        }
        match (&mut values, img) {
            (Values::U8(v), image::DynamicImage::ImageLuma8(b)) => v.extend_from_slice(b.as_raw()),
            (Values::U16(v), image::DynamicImage::ImageLuma16(b)) => {
                v.extend_from_slice(b.as_raw())
            }
            _ => return Err(invalid(p, "slice is not grayscale")),
        }
        Ok(())
    };
    push(&files[0], first)?;
    for p in &files[1..] {
        push(p, open(p)?)?;
    }
    let format = if files.len() == 1 && files[0] == path {
        "image (1 slice)".to_owned()
    } else {
        format!("image stack ({} slices)", files.len())
    };
    finish(path, dims, [1.0; 3], values, ty, format, opts, Vec::new())
}

fn depth(p: &Path, img: &image::DynamicImage) -> Result<ScalarType, ReadError> {
    match img {
        image::DynamicImage::ImageLuma8(_) => Ok(ScalarType::U8),
        image::DynamicImage::ImageLuma16(_) => Ok(ScalarType::U16),
        other => Err(invalid(
            p,
            format!("slice is {:?}, not 8 or 16-bit grayscale", other.color()),
        )),
    }
}
