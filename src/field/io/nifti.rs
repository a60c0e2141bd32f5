//! NIfTI-1 (`.nii`, `.nii.gz`, and `.hdr` + `.img` pairs), from the
//! 348-byte header:
//!
//! | offset | field | use |
//! |---|---|---|
//! | 0 | `sizeof_hdr` (i32) | 348; read byte-swapped it gives the byte order |
//! | 40 | `dim[8]` (i16) | `dim[0]` axes, `dim[1..=3]` sizes; higher axes must be 1 |
//! | 70 | `datatype` (i16) | 2 u8, 4 i16, 8 i32, 16 f32, 64 f64, 256 i8, 512 u16, 768 u32, 1024 i64, 1280 u64 |
//! | 72 | `bitpix` (i16) | must match the datatype |
//! | 76 | `pixdim[8]` (f32) | spacing from `pixdim[1..=3]` (absolute value) |
//! | 108 | `vox_offset` (f32) | data offset in a `.nii` |
//! | 112 | `scl_slope`, `scl_inter` (f32) | value = slope · stored + inter |
//! | 344 | `magic` | `n+1` (single file) or `ni1` (pair) |
//!
//! When `scl_slope` is nonzero and not (1, 0), values are scaled and become
//! float32 (from 8 and 16-bit data) or float64 (wider data). Padding after
//! the data is tolerated with a warning.

use super::data::{DataSpec, Encoding, Tail, read_data};
use super::{ReadError, ReadOptions, ScalarType, Volume, check_dims, finish, invalid, io_error};
use crate::field::Values;
use std::path::{Path, PathBuf};

/// True when `head` (a file's first bytes) looks like NIfTI-1 (or gzip,
/// which the caller resolves by extension).
pub fn sniff(head: &[u8]) -> bool {
    head.len() >= 348
        && (head[..4] == 348i32.to_le_bytes() || head[..4] == 348i32.to_be_bytes())
        && (head.get(344..347) == Some(b"n+1") || head.get(344..347) == Some(b"ni1"))
}

/// Reads a NIfTI-1 file.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let gz = is_gz(path)?;
    let mut f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let head = if gz {
        let mut d = flate2::read::MultiGzDecoder::new(std::io::BufReader::new(&mut f));
        super::read_prefix(&mut d, 348)
            .map_err(|e| invalid(path, format!("corrupt gzip data in the header: {e}")))?
    } else {
        super::read_prefix(&mut f, 348).map_err(|e| io_error(path, e))?
    };
    if head.len() < 348 {
        return Err(invalid(
            path,
            format!(
                "not a NIfTI-1 file: {} bytes, the header alone needs 348",
                head.len()
            ),
        ));
    }
    let le = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
    let big_endian = match le {
        348 => false,
        _ if i32::from_be_bytes([head[0], head[1], head[2], head[3]]) == 348 => true,
        540 => return Err(invalid(path, "NIfTI-2 is not supported (only NIfTI-1)")),
        _ => {
            return Err(invalid(
                path,
                "not a NIfTI-1 file (sizeof_hdr is not 348 in either byte order)",
            ));
        }
    };
    let i16_at = |o: usize| {
        let b = [head[o], head[o + 1]];
        if big_endian {
            i16::from_be_bytes(b)
        } else {
            i16::from_le_bytes(b)
        }
    };
    let f32_at = |o: usize| {
        let b = [head[o], head[o + 1], head[o + 2], head[o + 3]];
        if big_endian {
            f32::from_be_bytes(b)
        } else {
            f32::from_le_bytes(b)
        }
    };
    let magic = &head[344..347];
    let pair = match magic {
        b"n+1" => false,
        b"ni1" => true,
        _ => {
            return Err(invalid(
                path,
                "bad NIfTI-1 magic (expected 'n+1' or 'ni1'; Analyze 7.5 is not supported)",
            ));
        }
    };
    let dim: Vec<i16> = (0..8).map(|i| i16_at(40 + 2 * i)).collect();
    let ndim = dim[0];
    if !(1..=7).contains(&ndim) {
        return Err(invalid(
            path,
            format!("dim[0] = {ndim} is not a valid number of axes (1 to 7)"),
        ));
    }
    let ndim = ndim as usize;
    let mut dims = [1usize; 3];
    for (i, d) in dim.iter().enumerate().take(ndim + 1).skip(1) {
        if *d < 1 {
            return Err(invalid(path, format!("dim[{i}] = {d} must be at least 1")));
        }
        if i <= 3 {
            dims[i - 1] = *d as usize;
        } else if *d != 1 {
            return Err(invalid(
                path,
                format!(
                    "dim[{i}] = {d}: time series and vector volumes are not supported (only 3D scalars)"
                ),
            ));
        }
    }
    let datatype = i16_at(70);
    let bitpix = i16_at(72);
    let ty = match datatype {
        2 => ScalarType::U8,
        4 => ScalarType::I16,
        8 => ScalarType::I32,
        16 => ScalarType::F32,
        64 => ScalarType::F64,
        256 => ScalarType::I8,
        512 => ScalarType::U16,
        768 => ScalarType::U32,
        1024 => ScalarType::I64,
        1280 => ScalarType::U64,
        d => {
            return Err(invalid(
                path,
                format!(
                    "NIfTI datatype {d} is not supported (complex, RGB, float128 and unknown types)"
                ),
            ));
        }
    };
    if bitpix as usize != 8 * ty.size() {
        return Err(invalid(
            path,
            format!(
                "bitpix {bitpix} does not match datatype {datatype} ({})",
                ty.name()
            ),
        ));
    }
    let spacing = [f32_at(80) as f64, f32_at(84) as f64, f32_at(88) as f64];
    let vox_offset = f32_at(108);
    let (slope, inter) = (f32_at(112), f32_at(116));
    if !(0.0..=1e12).contains(&vox_offset) {
        return Err(invalid(path, format!("bad vox_offset {vox_offset}")));
    }
    let vox_offset = vox_offset as u64;
    let n = check_dims(path, dims, ty, opts)?;
    let (file, offset, skip, encoding) = if pair {
        let img = image_file(path)?;
        let igz = is_gz(&img)?;
        if igz {
            (img, 0, vox_offset, Encoding::Gzip)
        } else {
            (img, vox_offset, 0, Encoding::Raw)
        }
    } else {
        if vox_offset < 348 {
            return Err(invalid(
                path,
                format!("vox_offset {vox_offset} lies inside the 348-byte header"),
            ));
        }
        if gz {
            (path.to_owned(), 0, vox_offset, Encoding::Gzip)
        } else {
            (path.to_owned(), vox_offset, 0, Encoding::Raw)
        }
    };
    let spec = DataSpec {
        file,
        offset,
        skip_decoded: skip,
        encoding,
        ty,
        big_endian,
        count: n,
        tail: Tail::Warn,
    };
    let (mut values, warnings) = read_data(path, &spec)?;
    let scaled =
        slope.is_finite() && inter.is_finite() && slope != 0.0 && !(slope == 1.0 && inter == 0.0);
    if scaled {
        values = scale(values, ty, slope as f64, inter as f64);
    }
    let format = format!(
        "NIfTI-1 ({}{}{})",
        if pair { ".hdr/.img" } else { ".nii" },
        if encoding == Encoding::Gzip {
            ", gzip"
        } else {
            ""
        },
        if scaled {
            format!(", scaled by {slope} + {inter}")
        } else {
            String::new()
        }
    );
    finish(path, dims, spacing, values, ty, format, opts, warnings)
}

/// True when the file starts with the gzip magic.
fn is_gz(path: &Path) -> Result<bool, ReadError> {
    let mut f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let mut m = [0u8; 2];
    let got = super::data::read_full(&mut f, &mut m).map_err(|e| io_error(path, e))?;
    Ok(got == 2 && m == [0x1f, 0x8b])
}

/// The `.img` (or `.img.gz`) beside a `.hdr`.
fn image_file(hdr: &Path) -> Result<PathBuf, ReadError> {
    let name = hdr
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name
        .strip_suffix(".hdr.gz")
        .or_else(|| name.strip_suffix(".hdr"))
        .or_else(|| name.strip_suffix(".nii"))
        .unwrap_or(&name);
    for ext in [".img", ".img.gz"] {
        let p = hdr.with_file_name(format!("{stem}{ext}"));
        if p.exists() {
            return Ok(p);
        }
    }
    Err(invalid(
        hdr,
        format!("NIfTI pair header without its data file {stem}.img"),
    ))
}

/// value = slope · stored + inter, as float32 for 8 and 16-bit data (exact
/// enough) and float64 for wider data.
fn scale(values: Values, ty: ScalarType, slope: f64, inter: f64) -> Values {
    let n = values.len();
    if ty.size() <= 2 {
        Values::F32(
            (0..n)
                .map(|i| (values.get(i) * slope + inter) as f32)
                .collect(),
        )
    } else {
        match values {
            Values::F64(mut v) => {
                v.iter_mut().for_each(|x| *x = *x * slope + inter);
                Values::F64(v)
            }
            v => Values::F64((0..n).map(|i| v.get(i) * slope + inter).collect()),
        }
    }
}
