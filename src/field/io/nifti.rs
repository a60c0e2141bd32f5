//! NIfTI-1 and NIfTI-2 (`.nii`, `.nii.gz`, and `.hdr` + `.img` pairs),
//! from the 348-byte NIfTI-1 header (below) or the 540-byte NIfTI-2 header
//! (the same fields widened to i64 and f64, at their NIfTI-2 offsets; magic
//! `n+2`/`ni2` at byte 4):
//!
//! | offset | field | use |
//! |---|---|---|
//! | 0 | `sizeof_hdr` (i32) | 348; read byte-swapped it gives the byte order |
//! | 40 | `dim[8]` (i16) | `dim[0]` axes, `dim[1..=3]` sizes, `dim[4]` frames, `dim[5]` components (one of each is read: [`ReadOptions::frame`], [`ReadOptions::component`]); `dim[6..=7]` must be 1 |
//! | 70 | `datatype` (i16) | 2 u8, 4 i16, 8 i32, 16 f32, 64 f64, 256 i8, 512 u16, 768 u32, 1024 i64, 1280 u64 |
//! | 72 | `bitpix` (i16) | must match the datatype |
//! | 76 | `pixdim[8]` (f32) | spacing from `pixdim[1..=3]` (absolute value) |
//! | 108 | `vox_offset` (f32) | data offset in a `.nii` |
//! | 112 | `scl_slope`, `scl_inter` (f32) | value = slope · stored + inter |
//! | 252 | `qform_code`, `sform_code` (i16) | which transform places the grid |
//! | 256 | `quatern_b, c, d`, `qoffset_x, y, z` (f32) | the qform: a rotation and an origin |
//! | 280 | `srow_x, srow_y, srow_z` (4 f32 each) | the sform: an affine, rows of world = M · (i, j, k, 1) |
//! | 344 | `magic` | `n+1` (single file) or `ni1` (pair) |
//!
//! The grid is placed in RAS space (see [`Geometry`]) by the sform when
//! `sform_code > 0`, else by the qform when `qform_code > 0` (with
//! `pixdim[0]` as qfac, the sign of the third axis), else at the origin,
//! axis-aligned (NIfTI's "method 1"). With an sform, the spacing of an axis
//! is the length of its column (`pixdim` where the two agree).
//!
//! When `scl_slope` is nonzero and not (1, 0), values are scaled and become
//! float32 (from 8 and 16-bit data) or float64 (wider data). Padding after
//! the data is tolerated with a warning.

use super::data::{DataSpec, Encoding, Tail, read_data};
use super::{
    ReadError, ReadOptions, ScalarType, Volume, check_dims, finish, geometry_or_warn, invalid,
    io_error,
};
use crate::field::{Geometry, Space, Values};
use std::path::{Path, PathBuf};

/// True when `head` (a file's first bytes) looks like NIfTI-1 or NIfTI-2
/// (or gzip, which the caller resolves by extension).
pub fn sniff(head: &[u8]) -> bool {
    let v1 = head.len() >= HEADER_1
        && (head[..4] == 348i32.to_le_bytes() || head[..4] == 348i32.to_be_bytes())
        && (head.get(344..347) == Some(b"n+1") || head.get(344..347) == Some(b"ni1"));
    let v2 = head.len() >= 8
        && (head[..4] == 540i32.to_le_bytes() || head[..4] == 540i32.to_be_bytes())
        && (head.get(4..7) == Some(b"n+2") || head.get(4..7) == Some(b"ni2"));
    v1 || v2
}

/// The fields of a NIfTI-1 or NIfTI-2 header the reader uses, in one
/// form (NIfTI-2 widens them: i64 dims, f64 pixdim and transforms).
struct Header {
    version: u8,
    pair: bool,
    big_endian: bool,
    dim: [i64; 8],
    datatype: i16,
    bitpix: i16,
    pixdim: [f64; 8],
    vox_offset: f64,
    slope: f64,
    inter: f64,
    qform_code: i32,
    sform_code: i32,
    quatern: [f64; 3],
    qoffset: [f64; 3],
    srow: [[f64; 4]; 3],
}

/// Bytes of the NIfTI-1 and NIfTI-2 headers.
const HEADER_1: usize = 348;
const HEADER_2: usize = 540;

fn parse_header(path: &Path, head: &[u8]) -> Result<Header, ReadError> {
    if head.len() < 4 {
        return Err(invalid(path, "not a NIfTI file: shorter than its header"));
    }
    let first: [u8; 4] = [head[0], head[1], head[2], head[3]];
    let (version, big_endian) = match (i32::from_le_bytes(first), i32::from_be_bytes(first)) {
        (348, _) => (1, false),
        (_, 348) => (1, true),
        (540, _) => (2, false),
        (_, 540) => (2, true),
        _ => {
            return Err(invalid(
                path,
                "not a NIfTI file (sizeof_hdr is neither 348 nor 540 in either byte order)",
            ));
        }
    };
    let size = if version == 1 { HEADER_1 } else { HEADER_2 };
    if head.len() < size {
        return Err(invalid(
            path,
            format!(
                "not a NIfTI-{version} file: {} bytes, the header alone needs {size}",
                head.len()
            ),
        ));
    }
    let bytes = |o: usize, n: usize| {
        let mut b = head[o..o + n].to_vec();
        if big_endian {
            b.reverse();
        }
        b
    };
    let i16_at = |o: usize| {
        let b = bytes(o, 2);
        i16::from_le_bytes([b[0], b[1]])
    };
    let i32_at = |o: usize| i32::from_le_bytes(bytes(o, 4).try_into().unwrap_or([0; 4]));
    let i64_at = |o: usize| i64::from_le_bytes(bytes(o, 8).try_into().unwrap_or([0; 8]));
    let f32_at = |o: usize| f32::from_le_bytes(bytes(o, 4).try_into().unwrap_or([0; 4])) as f64;
    let f64_at = |o: usize| f64::from_le_bytes(bytes(o, 8).try_into().unwrap_or([0; 8]));
    if version == 1 {
        let pair = match &head[344..347] {
            b"n+1" => false,
            b"ni1" => true,
            _ => {
                return Err(invalid(
                    path,
                    "bad NIfTI-1 magic (expected 'n+1' or 'ni1'; Analyze 7.5 is not supported)",
                ));
            }
        };
        Ok(Header {
            version,
            pair,
            big_endian,
            dim: std::array::from_fn(|i| i16_at(40 + 2 * i) as i64),
            datatype: i16_at(70),
            bitpix: i16_at(72),
            pixdim: std::array::from_fn(|i| f32_at(76 + 4 * i)),
            vox_offset: f32_at(108),
            slope: f32_at(112),
            inter: f32_at(116),
            qform_code: i16_at(252) as i32,
            sform_code: i16_at(254) as i32,
            quatern: [f32_at(256), f32_at(260), f32_at(264)],
            qoffset: [f32_at(268), f32_at(272), f32_at(276)],
            srow: [280, 296, 312].map(|o| std::array::from_fn(|k| f32_at(o + 4 * k))),
        })
    } else {
        let pair = match &head[4..7] {
            b"n+2" => false,
            b"ni2" => true,
            _ => return Err(invalid(path, "bad NIfTI-2 magic (expected 'n+2' or 'ni2')")),
        };
        Ok(Header {
            version,
            pair,
            big_endian,
            dim: std::array::from_fn(|i| i64_at(16 + 8 * i)),
            datatype: i16_at(12),
            bitpix: i16_at(14),
            pixdim: std::array::from_fn(|i| f64_at(104 + 8 * i)),
            vox_offset: i64_at(168) as f64,
            slope: f64_at(176),
            inter: f64_at(184),
            qform_code: i32_at(344),
            sform_code: i32_at(348),
            quatern: [f64_at(352), f64_at(360), f64_at(368)],
            qoffset: [f64_at(376), f64_at(384), f64_at(392)],
            srow: [400, 432, 464].map(|o| std::array::from_fn(|k| f64_at(o + 8 * k))),
        })
    }
}

/// Reads a NIfTI-1 or NIfTI-2 file.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let gz = is_gz(path)?;
    let mut f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let head = if gz {
        let mut d = flate2::read::MultiGzDecoder::new(std::io::BufReader::new(&mut f));
        super::read_prefix(&mut d, HEADER_2)
            .map_err(|e| invalid(path, format!("corrupt gzip data in the header: {e}")))?
    } else {
        super::read_prefix(&mut f, HEADER_2).map_err(|e| io_error(path, e))?
    };
    let h = parse_header(path, &head)?;
    let (pair, big_endian) = (h.pair, h.big_endian);
    let dim = h.dim;
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
        } else if i >= 6 && *d != 1 {
            return Err(invalid(
                path,
                format!("dim[{i}] = {d}: only time (dim[4]) and vector (dim[5]) axes are read"),
            ));
        }
    }
    // Frames (dim[4], time) and components (dim[5]) are whole 3D blocks,
    // frames faster: block = component · frames + frame.
    let axis = |i: usize| if ndim >= i { dim[i].max(1) as usize } else { 1 };
    let (frames, components) = (axis(4), axis(5));
    let frame = super::choose(path, super::Several::Frames, frames, opts)?;
    let component = super::choose(path, super::Several::Components, components, opts)?;
    let block = (component * frames + frame) as u64;
    let (datatype, bitpix) = (h.datatype, h.bitpix);
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
    let spacing = [h.pixdim[1], h.pixdim[2], h.pixdim[3]];
    let vox_offset = h.vox_offset;
    let (slope, inter) = (h.slope, h.inter);
    if !(0.0..=1e12).contains(&vox_offset) {
        return Err(invalid(path, format!("bad vox_offset {vox_offset}")));
    }
    let vox_offset = vox_offset as u64;
    let n = check_dims(path, dims, ty, opts)?;
    let block_offset = block * n as u64 * ty.size() as u64;
    let (file, offset, skip, encoding) = if pair {
        let img = image_file(path)?;
        let igz = is_gz(&img)?;
        if igz {
            (img, 0, vox_offset + block_offset, Encoding::Gzip)
        } else {
            (img, vox_offset + block_offset, 0, Encoding::Raw)
        }
    } else {
        let header = if h.version == 1 { HEADER_1 } else { HEADER_2 } as u64;
        if vox_offset < header {
            return Err(invalid(
                path,
                format!("vox_offset {vox_offset} lies inside the {header}-byte header"),
            ));
        }
        if gz {
            (
                path.to_owned(),
                0,
                vox_offset + block_offset,
                Encoding::Gzip,
            )
        } else {
            (path.to_owned(), vox_offset + block_offset, 0, Encoding::Raw)
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
        // The other frames and components follow the one read.
        tail: if frames * components > 1 {
            Tail::Ignore
        } else {
            Tail::Warn
        },
    };
    let (mut values, mut warnings) = read_data(path, &spec)?;
    let scaled =
        slope.is_finite() && inter.is_finite() && slope != 0.0 && !(slope == 1.0 && inter == 0.0);
    if scaled {
        values = scale(values, ty, slope, inter);
    }
    let format = format!(
        "NIfTI-{} ({}{}{}{}{})",
        h.version,
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
        },
        super::choice_note(super::Several::Frames, frame, frames),
        super::choice_note(super::Several::Components, component, components),
    );
    let (spacing, geometry) = placement(&h, spacing, &mut warnings);
    Ok(finish(path, dims, spacing, values, ty, format, opts, warnings)?.placed(geometry))
}

/// The spacing and geometry of a NIfTI header (see the module doc): by the
/// sform, the qform, or neither.
fn placement(h: &Header, pixdim: [f64; 3], warnings: &mut Vec<String>) -> ([f64; 3], Geometry) {
    if h.sform_code > 0 {
        let rows = h.srow;
        let axes: [[f64; 3]; 3] = std::array::from_fn(|a| std::array::from_fn(|c| rows[c][a]));
        // The columns' lengths, unless pixdim says the same up to the
        // header's float32 rounding (then pixdim, as every tool shows it).
        let mut spacing = axes.map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt());
        for (s, p) in spacing.iter_mut().zip(pixdim) {
            if (*s - p.abs()).abs() <= 1e-5 * s.abs() {
                *s = p.abs();
            }
        }
        let origin = [rows[0][3], rows[1][3], rows[2][3]];
        return (
            spacing,
            geometry_or_warn(origin, axes, Space::Ras, warnings),
        );
    }
    if h.qform_code > 0 {
        let [b, c, d] = h.quatern;
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let qfac = if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        // The rotation's columns are the axis directions; qfac flips the
        // third.
        let r = [
            [
                a * a + b * b - c * c - d * d,
                2.0 * (b * c + a * d),
                2.0 * (b * d - a * c),
            ],
            [
                2.0 * (b * c - a * d),
                a * a + c * c - b * b - d * d,
                2.0 * (c * d + a * b),
            ],
            [
                qfac * 2.0 * (b * d + a * c),
                qfac * 2.0 * (c * d - a * b),
                qfac * (a * a + d * d - c * c - b * b),
            ],
        ];
        return (pixdim, geometry_or_warn(h.qoffset, r, Space::Ras, warnings));
    }
    (
        pixdim,
        Geometry {
            space: Space::Ras,
            ..Geometry::IDENTITY
        },
    )
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
