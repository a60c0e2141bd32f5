//! TIFF through the `tiff` crate: a plain 2D image (one page), or a 3D
//! volume as a multi-page TIFF (one page per z, as tifffile, SimpleITK and
//! ImageJ write them).
//!
//! Every page must be grayscale with one sample per pixel (8, 16 or 32-bit
//! integers, signed or not, or 32/64-bit float; 16-bit float becomes
//! float32), all pages of one size and type. Anything else (RGB, palette,
//! an alpha channel, several samples, pages of different sizes, an ImageJ
//! hyperstack with several channels or frames) is an error that says what
//! was found, never a silent misread.

use super::{ReadError, ScalarType, invalid, io_error};
use crate::field::Values;
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult, Limits};

/// The pages of a TIFF file: width, height, page count, the values of all
/// pages (x fastest, then y, then page), and the file's scalar type.
pub(crate) struct Pages {
    pub(crate) dims: [usize; 3],
    pub(crate) values: Values,
    pub(crate) scalar_type: ScalarType,
}

fn tiff_error(path: &Path, e: tiff::TiffError) -> ReadError {
    match e {
        tiff::TiffError::IoError(e) => io_error(path, e),
        e => invalid(path, format!("cannot decode TIFF: {e}")),
    }
}

/// Checks every page's layout and counts them, without decoding pixels;
/// `check` gets the dimensions (width, height, pages) before anything is
/// allocated.
pub(crate) fn read(
    path: &Path,
    check: impl FnOnce([usize; 3], ScalarType) -> Result<(), ReadError>,
) -> Result<Pages, ReadError> {
    let file = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let mut dec = Decoder::new(std::io::BufReader::new(file))
        .map_err(|e| tiff_error(path, e))?
        .with_limits(Limits::unlimited());
    if let Ok(desc) = dec.get_tag_ascii_string(tiff::tags::Tag::ImageDescription)
        && desc.starts_with("ImageJ=")
    {
        for key in ["channels", "frames"] {
            let n = desc
                .lines()
                .find_map(|l| l.strip_prefix(key)?.strip_prefix('='))
                .and_then(|v| v.trim().parse::<u64>().ok())
                .unwrap_or(1);
            if n > 1 {
                return Err(invalid(
                    path,
                    format!(
                        "ImageJ hyperstack with {n} {key}: only one channel and one frame \
                         (a 3D scalar volume) can be read"
                    ),
                ));
            }
        }
    }
    let (w, h) = dec.dimensions().map_err(|e| tiff_error(path, e))?;
    let mut pages = 0usize;
    loop {
        pages += 1;
        let page = pages;
        let size = dec.dimensions().map_err(|e| tiff_error(path, e))?;
        if size != (w, h) {
            return Err(invalid(
                path,
                format!(
                    "page {page} is {}x{} but page 1 is {w}x{h}: not one 3D volume",
                    size.0, size.1
                ),
            ));
        }
        match dec.colortype().map_err(|e| tiff_error(path, e))? {
            tiff::ColorType::Gray(_) => {}
            tiff::ColorType::Multiband { num_samples: 1, .. } => {}
            other => {
                return Err(invalid(
                    path,
                    format!(
                        "page {page} is {other:?}: only grayscale TIFF (one sample per pixel) \
                         is read"
                    ),
                ));
            }
        }
        if !dec.more_images() {
            break;
        }
        dec.next_image().map_err(|e| tiff_error(path, e))?;
    }
    dec.seek_to_image(0).map_err(|e| tiff_error(path, e))?;
    let dims = [w as usize, h as usize, pages];
    let first = dec.read_image().map_err(|e| tiff_error(path, e))?;
    let scalar_type = type_of(path, &first)?;
    check(dims, scalar_type)?;
    let mut values = empty(scalar_type, dims.iter().product());
    append(path, &mut values, first, 1)?;
    for page in 2..=pages {
        dec.next_image().map_err(|e| tiff_error(path, e))?;
        let data = dec.read_image().map_err(|e| tiff_error(path, e))?;
        if type_of(path, &data)? != scalar_type {
            return Err(invalid(
                path,
                format!(
                    "page {page} holds {} but page 1 holds {}: not one volume",
                    type_of(path, &data)?.name(),
                    scalar_type.name()
                ),
            ));
        }
        append(path, &mut values, data, page)?;
    }
    if values.len() != dims.iter().product::<usize>() {
        return Err(invalid(
            path,
            format!("pages hold {} values, not {w}x{h}x{pages}", values.len()),
        ));
    }
    Ok(Pages {
        dims,
        values,
        scalar_type,
    })
}

fn type_of(path: &Path, d: &DecodingResult) -> Result<ScalarType, ReadError> {
    Ok(match d {
        DecodingResult::U8(_) => ScalarType::U8,
        DecodingResult::I8(_) => ScalarType::I8,
        DecodingResult::U16(_) => ScalarType::U16,
        DecodingResult::I16(_) => ScalarType::I16,
        DecodingResult::U32(_) => ScalarType::U32,
        DecodingResult::I32(_) => ScalarType::I32,
        DecodingResult::F16(_) | DecodingResult::F32(_) => ScalarType::F32,
        DecodingResult::F64(_) => ScalarType::F64,
        DecodingResult::U64(_) | DecodingResult::I64(_) => {
            return Err(invalid(path, "64-bit integer TIFF is not supported"));
        }
    })
}

fn empty(ty: ScalarType, n: usize) -> Values {
    match ty {
        ScalarType::U8 => Values::U8(Vec::with_capacity(n)),
        ScalarType::I8 => Values::I8(Vec::with_capacity(n)),
        ScalarType::U16 => Values::U16(Vec::with_capacity(n)),
        ScalarType::I16 => Values::I16(Vec::with_capacity(n)),
        ScalarType::U32 => Values::U32(Vec::with_capacity(n)),
        ScalarType::I32 => Values::I32(Vec::with_capacity(n)),
        ScalarType::F32 => Values::F32(Vec::with_capacity(n)),
        _ => Values::F64(Vec::with_capacity(n)),
    }
}

fn append(
    path: &Path,
    values: &mut Values,
    d: DecodingResult,
    page: usize,
) -> Result<(), ReadError> {
    match (values, d) {
        (Values::U8(v), DecodingResult::U8(d)) => v.extend_from_slice(&d),
        (Values::I8(v), DecodingResult::I8(d)) => v.extend_from_slice(&d),
        (Values::U16(v), DecodingResult::U16(d)) => v.extend_from_slice(&d),
        (Values::I16(v), DecodingResult::I16(d)) => v.extend_from_slice(&d),
        (Values::U32(v), DecodingResult::U32(d)) => v.extend_from_slice(&d),
        (Values::I32(v), DecodingResult::I32(d)) => v.extend_from_slice(&d),
        (Values::F32(v), DecodingResult::F32(d)) => v.extend_from_slice(&d),
        (Values::F32(v), DecodingResult::F16(d)) => v.extend(d.iter().map(|x| x.to_f32())),
        (Values::F64(v), DecodingResult::F64(d)) => v.extend_from_slice(&d),
        _ => {
            return Err(invalid(
                path,
                format!("page {page} changes the sample type"),
            ));
        }
    }
    Ok(())
}
