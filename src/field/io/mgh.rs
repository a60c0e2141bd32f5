//! FreeSurfer MGH (`.mgh`) and its gzip form (`.mgz`): a 284-byte
//! big-endian header, then the data.
//!
//! | offset | field | use |
//! |---|---|---|
//! | 0 | `version` (i32) | 1 |
//! | 4 | `width, height, depth, nframes` (i32) | dims; one frame is read ([`super::ReadOptions::frame`]) |
//! | 20 | `type` (i32) | 0 uint8, 1 int32, 3 float32, 4 int16 |
//! | 28 | `goodRASflag` (i16) | when 1, the geometry below is valid |
//! | 30 | `spacing` (3 f32) | voxel size |
//! | 42 | `Mdc` (9 f32) | direction cosines of the x, y, z axes (columns) |
//! | 78 | `c_ras` (3 f32) | the RAS position of the volume's centre |
//!
//! The grid is placed in RAS space: vertex 0 lies at
//! `c_ras - Σ_a Mdc_a · spacing_a · dim_a / 2`, as FreeSurfer computes it.
//! Without `goodRASflag` the spacing is 1 and the grid axis-aligned at the
//! origin. Trailing data (FreeSurfer's optional tags) is ignored.

use super::data::{DataSpec, Encoding, Tail, read_data};
use super::{
    ReadError, ReadOptions, ScalarType, Volume, check_dims, finish, geometry_or_warn, invalid,
    io_error,
};
use crate::field::Space;
use std::path::Path;

/// Bytes of the header; the data starts here.
const HEADER: usize = 284;

/// Reads a `.mgh` or `.mgz` file.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let mut f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let magic = super::read_prefix(&mut f, 2).map_err(|e| io_error(path, e))?;
    let gz = magic == [0x1f, 0x8b];
    let mut f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let head = if gz {
        let mut d = flate2::read::MultiGzDecoder::new(std::io::BufReader::new(&mut f));
        super::read_prefix(&mut d, HEADER)
            .map_err(|e| invalid(path, format!("corrupt gzip data in the header: {e}")))?
    } else {
        super::read_prefix(&mut f, HEADER).map_err(|e| io_error(path, e))?
    };
    if head.len() < HEADER {
        return Err(invalid(
            path,
            format!(
                "not an MGH file: {} bytes, the header alone needs {HEADER}",
                head.len()
            ),
        ));
    }
    let i32_at = |o: usize| i32::from_be_bytes([head[o], head[o + 1], head[o + 2], head[o + 3]]);
    let f32_at = |o: usize| {
        f64::from(f32::from_be_bytes([
            head[o],
            head[o + 1],
            head[o + 2],
            head[o + 3],
        ]))
    };
    let version = i32_at(0);
    if version != 1 {
        return Err(invalid(
            path,
            format!("MGH version {version} is not supported (only 1; not an MGH file?)"),
        ));
    }
    let sizes = [i32_at(4), i32_at(8), i32_at(12)];
    let frames = i32_at(16);
    if sizes.iter().any(|&s| s < 1) {
        return Err(invalid(path, format!("bad dimensions {sizes:?}")));
    }
    if frames < 1 {
        return Err(invalid(path, format!("bad frame count {frames}")));
    }
    let frames = frames as usize;
    let frame = super::choose(path, super::Several::Frames, frames, opts)?;
    super::choose(path, super::Several::Components, 1, opts)?;
    let dims = sizes.map(|s| s as usize);
    let ty = match i32_at(20) {
        0 => ScalarType::U8,
        1 => ScalarType::I32,
        3 => ScalarType::F32,
        4 => ScalarType::I16,
        t => {
            return Err(invalid(
                path,
                format!("MGH type {t} is not supported (0 uchar, 1 int, 3 float, 4 short)"),
            ));
        }
    };
    let n = check_dims(path, dims, ty, opts)?;
    // Frames are whole volumes one after the other.
    let start = HEADER as u64 + (frame * n * ty.size()) as u64;
    let (offset, skip, encoding) = if gz {
        (0, start, Encoding::Gzip)
    } else {
        (start, 0, Encoding::Raw)
    };
    let spec = DataSpec {
        file: path.to_owned(),
        offset,
        skip_decoded: skip,
        encoding,
        ty,
        big_endian: true,
        count: n,
        tail: Tail::Ignore,
    };
    let (values, mut warnings) = read_data(path, &spec)?;
    let good_ras = i16::from_be_bytes([head[28], head[29]]) == 1;
    let (spacing, geometry) = if good_ras {
        let spacing = [f32_at(30), f32_at(34), f32_at(38)];
        let axes: [[f64; 3]; 3] =
            std::array::from_fn(|a| [0, 1, 2].map(|c| f32_at(42 + 12 * a + 4 * c)));
        let centre = [f32_at(78), f32_at(82), f32_at(86)];
        let origin = std::array::from_fn(|c| {
            centre[c]
                - (0..3)
                    .map(|a| axes[a][c] * spacing[a] * dims[a] as f64 / 2.0)
                    .sum::<f64>()
        });
        (
            spacing,
            geometry_or_warn(origin, axes, Space::Ras, &mut warnings),
        )
    } else {
        (
            [1.0; 3],
            crate::field::Geometry {
                space: Space::Ras,
                ..crate::field::Geometry::IDENTITY
            },
        )
    };
    let format = format!(
        "MGH ({}{})",
        if gz { ".mgz, gzip" } else { ".mgh" },
        super::choice_note(super::Several::Frames, frame, frames)
    );
    Ok(finish(path, dims, spacing, values, ty, format, opts, warnings)?.placed(geometry))
}
