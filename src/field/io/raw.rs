//! Headerless raw files: the layout comes from the name
//! (`NAME_XxYxZ_TYPE.raw`, e.g. `neghip_64x64x64_uint8.raw`, little-endian;
//! `NAME_XxY_TYPE.raw` for an image) or from [`ReadOptions::raw`] (the CLI's
//! `--dims X,Y,Z --type T --endian big|little`).
//!
//! The file must hold exactly X·Y·Z values: a raw file has no header to
//! tell padding from a wrong layout, so both shorter and longer files are
//! errors.

use super::data::{DataSpec, Encoding, Tail, read_data};
use super::{RawLayout, ReadError, ReadOptions, ScalarType, Volume, check_dims, finish, invalid};
use std::path::Path;

/// The layout a file name carries: `NAME_XxYxZ_TYPE.raw` (or `XxY`).
pub fn layout_from_name(path: &Path) -> Option<([usize; 3], ScalarType)> {
    let name = path.file_name()?.to_str()?;
    let stem = name
        .strip_suffix(".raw")
        .or_else(|| name.strip_suffix(".RAW"))?;
    let mut parts = stem.rsplitn(3, '_');
    let ty = ScalarType::parse(parts.next()?)?;
    let dims_text = parts.next()?;
    parts.next()?; // a NAME must precede
    let d: Vec<usize> = dims_text
        .split(['x', 'X'])
        .map(|t| t.parse().ok())
        .collect::<Option<_>>()?;
    let dims = match d.as_slice() {
        [x, y] => [*x, *y, 1],
        [x, y, z] => [*x, *y, *z],
        _ => return None,
    };
    Some((dims, ty))
}

/// Reads a `.raw` file whose name carries its layout.
pub fn read_by_name(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let (dims, ty) = layout_from_name(path).ok_or_else(|| {
        invalid(
            path,
            "raw file without layout: name it NAME_XxYxZ_TYPE.raw (e.g. head_256x256x128_uint16.raw) \
             or give --dims X,Y,Z --type T [--endian big]",
        )
    })?;
    read_layout(path, dims, ty, false, opts)
}

/// Reads any file as raw with the given layout.
pub fn read(path: &Path, layout: &RawLayout, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let ty = ScalarType::parse(&layout.scalar_type).ok_or_else(|| {
        invalid(
            path,
            format!(
                "unknown type '{}' (uint8, int8, uint16, int16, uint32, int32, uint64, int64, float32, float64)",
                super::clip(&layout.scalar_type)
            ),
        )
    })?;
    read_layout(path, layout.dims, ty, layout.big_endian, opts)
}

fn read_layout(
    path: &Path,
    dims: [usize; 3],
    ty: ScalarType,
    big_endian: bool,
    opts: &ReadOptions,
) -> Result<Volume, ReadError> {
    let n = check_dims(path, dims, ty, opts)?;
    let spec = DataSpec {
        file: path.to_owned(),
        offset: 0,
        skip_decoded: 0,
        encoding: Encoding::Raw,
        ty,
        big_endian,
        count: n,
        tail: Tail::Error,
    };
    let (values, warnings) = read_data(path, &spec)?;
    let format = format!(
        "raw ({}{})",
        ty.name(),
        if big_endian && ty.size() > 1 {
            ", big-endian"
        } else {
            ""
        }
    );
    finish(path, dims, [1.0; 3], values, ty, format, opts, warnings)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn names_carry_layouts() {
        let l = |s: &str| layout_from_name(Path::new(s));
        assert_eq!(
            l("/d/neghip_64x64x64_uint8.raw"),
            Some(([64, 64, 64], ScalarType::U8))
        );
        assert_eq!(
            l("my_head_2x3x4_float32.raw"),
            Some(([2, 3, 4], ScalarType::F32))
        );
        assert_eq!(l("img_5x7_int16.raw"), Some(([5, 7, 1], ScalarType::I16)));
        assert_eq!(l("64x64x64_uint8.raw"), None);
        assert_eq!(l("a_64x64x64_complex.raw"), None);
        assert_eq!(l("a_64xx64_uint8.raw"), None);
    }
}
