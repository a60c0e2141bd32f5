//! MetaImage (ITK): `.mha` with the data attached after the
//! `ElementDataFile = LOCAL` line, or `.mhd` naming a data file (`.raw`,
//! or zlib-compressed `.zraw`).
//!
//! Read: `NDims` (1 to 4; a fourth axis is time, one frame read:
//! [`super::ReadOptions::frame`]), `DimSize`, `ElementType` (`MET_UCHAR` ...
//! `MET_DOUBLE`; `MET_LONG` is 4 bytes as in MetaIO), `ElementSpacing` (or
//! `ElementSize`), `BinaryDataByteOrderMSB` / `ElementByteOrderMSB`,
//! `CompressedData`, `BinaryData` (False: ASCII), `HeaderSize` (bytes to
//! skip in the data file; -1: the data ends the file), and
//! `ElementNumberOfChannels` (interleaved
//! components, one read: [`super::ReadOptions::component`]), and the geometry in ITK's LPS
//! space: `Offset` (or `Position`, `Origin`) and `TransformMatrix` (or
//! `Rotation`, `Orientation`), whose first three numbers are the
//! direction of the first axis. Keys are matched without case.

use super::data::{DataSpec, Encoding, Tail, read_data};
use super::{
    ReadError, ReadOptions, ScalarType, Volume, check_dims, clip, finish, geometry_or_warn,
    invalid, io_error,
};
use crate::field::{Geometry, Space};
use std::path::Path;

const MAX_HEADER: usize = 1 << 20;

/// Reads a `.mha` or `.mhd` file.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let (lines, data_offset) = super::read_header_lines(path, MAX_HEADER, |line| {
        line.split_once('=')
            .is_some_and(|(k, _)| k.trim().eq_ignore_ascii_case("ElementDataFile"))
    })?;
    let mut fields: Vec<(String, String)> = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let Some((k, v)) = line.split_once('=') else {
            return Err(invalid(
                path,
                format!(
                    "header line {}: expected 'Key = Value', found '{}' (not a MetaImage file?)",
                    i + 1,
                    clip(line)
                ),
            ));
        };
        fields.push((k.trim().to_ascii_lowercase(), v.trim().to_owned()));
    }
    let get = |key: &str| {
        fields
            .iter()
            .find(|(k, _)| k == &key.to_ascii_lowercase())
            .map(|(_, v)| v.as_str())
    };
    let boolean = |key: &str| -> Result<Option<bool>, ReadError> {
        match get(key).map(str::to_ascii_lowercase).as_deref() {
            None => Ok(None),
            Some("true") | Some("1") => Ok(Some(true)),
            Some("false") | Some("0") => Ok(Some(false)),
            Some(other) => Err(invalid(
                path,
                format!("'{key}' must be True or False, not '{}'", clip(other)),
            )),
        }
    };
    let file_name = get("ElementDataFile")
        .ok_or_else(|| invalid(path, "missing 'ElementDataFile' (not a MetaImage file?)"))?;
    let ndims: usize = get("NDims")
        .ok_or_else(|| invalid(path, "missing 'NDims'"))?
        .parse()
        .map_err(|_| invalid(path, "'NDims' is not a number"))?;
    if !(1..=4).contains(&ndims) {
        return Err(invalid(
            path,
            format!("NDims {ndims} is not supported (1 to 4)"),
        ));
    }
    // The axes of space: a fourth is time (ITK writes a 4D image's
    // frames one after the other, x fastest).
    let space = ndims.min(3);
    let sizes: Vec<usize> = get("DimSize")
        .ok_or_else(|| invalid(path, "missing 'DimSize'"))
        .and_then(|v| {
            super::parse_numbers(v)
                .ok_or_else(|| invalid(path, format!("bad 'DimSize': '{}'", clip(v))))
        })?;
    if sizes.len() != ndims {
        return Err(invalid(
            path,
            format!("'DimSize' has {} numbers but NDims is {ndims}", sizes.len()),
        ));
    }
    let mut dims = [1usize; 3];
    dims[..space].copy_from_slice(&sizes[..space]);
    let frames = if ndims == 4 { sizes[3] } else { 1 };
    if frames == 0 {
        return Err(invalid(path, "'DimSize' has 0 frames"));
    }
    let channels_text = get("ElementNumberOfChannels").unwrap_or("1");
    let channels: usize = match channels_text.trim().parse() {
        Ok(c) if c >= 1 => c,
        _ => {
            return Err(invalid(
                path,
                format!("bad 'ElementNumberOfChannels': '{}'", clip(channels_text)),
            ));
        }
    };
    let frame = super::choose(path, super::Several::Frames, frames, opts)?;
    let component = super::choose(path, super::Several::Components, channels, opts)?;
    let et = get("ElementType").ok_or_else(|| invalid(path, "missing 'ElementType'"))?;
    let ty = match et.to_ascii_uppercase().as_str() {
        "MET_UCHAR" => ScalarType::U8,
        "MET_CHAR" => ScalarType::I8,
        "MET_USHORT" => ScalarType::U16,
        "MET_SHORT" => ScalarType::I16,
        "MET_UINT" | "MET_ULONG" => ScalarType::U32,
        "MET_INT" | "MET_LONG" => ScalarType::I32,
        "MET_ULONG_LONG" => ScalarType::U64,
        "MET_LONG_LONG" => ScalarType::I64,
        "MET_FLOAT" => ScalarType::F32,
        "MET_DOUBLE" => ScalarType::F64,
        other => {
            return Err(invalid(
                path,
                format!("unknown or unsupported ElementType '{}'", clip(other)),
            ));
        }
    };
    let mut spacing = [1.0f64; 3];
    if let Some(v) = get("ElementSpacing").or_else(|| get("ElementSize")) {
        let s: Vec<f64> = super::parse_numbers(v)
            .ok_or_else(|| invalid(path, format!("bad 'ElementSpacing': '{}'", clip(v))))?;
        if s.len() != ndims {
            return Err(invalid(
                path,
                format!(
                    "'ElementSpacing' has {} numbers but NDims is {ndims}",
                    s.len()
                ),
            ));
        }
        spacing[..space].copy_from_slice(&s[..space]);
    }
    let big_endian = boolean("BinaryDataByteOrderMSB")?
        .or(boolean("ElementByteOrderMSB")?)
        .unwrap_or(false);
    let compressed = boolean("CompressedData")?.unwrap_or(false);
    let binary = boolean("BinaryData")?.unwrap_or(true);
    let encoding = match (binary, compressed) {
        (_, true) => Encoding::Zlib,
        (true, false) => Encoding::Raw,
        (false, false) => Encoding::Ascii,
    };
    let header_size: i64 = match get("HeaderSize") {
        None => 0,
        Some(v) => v
            .parse()
            .map_err(|_| invalid(path, format!("bad 'HeaderSize': '{}'", clip(v))))?,
    };
    let n = check_dims(path, dims, ty, opts)?;
    // Channels are interleaved (the fastest axis), frames follow one
    // another (the slowest): all are read, one of each kept.
    let stored = match (dims[0].checked_mul(channels), dims[2].checked_mul(frames)) {
        (Some(x), Some(z)) => check_dims(path, [x, dims[1], z], ty, opts)?,
        _ => {
            return Err(invalid(
                path,
                format!("{channels} channels of {frames} frames overflow"),
            ));
        }
    };
    let local = file_name.eq_ignore_ascii_case("LOCAL");
    let data_file = if local {
        if data_offset == usize::MAX {
            return Err(invalid(
                path,
                "'ElementDataFile = LOCAL' must end the header",
            ));
        }
        path.to_owned()
    } else {
        if file_name.eq_ignore_ascii_case("LIST")
            || file_name.contains('%')
            || file_name.split_whitespace().count() > 1
        {
            return Err(invalid(
                path,
                format!(
                    "ElementDataFile '{}' is a file list, which is not supported",
                    clip(file_name)
                ),
            ));
        }
        path.parent().unwrap_or(Path::new(".")).join(file_name)
    };
    let base = if local { data_offset as u64 } else { 0 };
    let offset = match header_size {
        -1 if encoding == Encoding::Raw => {
            let len = std::fs::metadata(&data_file)
                .map_err(|e| io_error(&data_file, e))?
                .len();
            let need = stored as u64 * ty.size() as u64;
            if len < base + need {
                return Err(invalid(
                    &data_file,
                    format!(
                        "data truncated: the header promises {need} bytes but the file has only {}",
                        len.saturating_sub(base)
                    ),
                ));
            }
            len - need
        }
        h if h < 0 => {
            return Err(invalid(
                path,
                format!("'HeaderSize = {h}' is not supported here"),
            ));
        }
        h => base + h as u64,
    };
    let spec = DataSpec {
        file: data_file,
        offset,
        skip_decoded: 0,
        encoding,
        ty,
        big_endian,
        count: stored,
        tail: Tail::Error,
    };
    let (values, mut warnings) = read_data(path, &spec)?;
    let values = super::select(values, n * channels, frames, frame, super::Several::Frames);
    let values = super::select(values, n, channels, component, super::Several::Components);
    let format = format!(
        "MetaImage ({}, {}{}{})",
        if local { ".mha" } else { ".mhd" },
        encoding.name(),
        super::choice_note(super::Several::Frames, frame, frames),
        super::choice_note(super::Several::Components, component, channels)
    );
    let numbers = |keys: &[&str], want: usize| -> Result<Option<Vec<f64>>, ReadError> {
        let Some((key, v)) = keys.iter().find_map(|k| get(k).map(|v| (k, v))) else {
            return Ok(None);
        };
        match super::parse_numbers::<f64>(v) {
            Some(n) if n.len() == want => Ok(Some(n)),
            _ => Err(invalid(
                path,
                format!("bad '{key}': '{}' (expected {want} numbers)", clip(v)),
            )),
        }
    };
    let origin = numbers(&["Offset", "Position", "Origin"], ndims)?;
    let matrix = numbers(
        &["TransformMatrix", "Rotation", "Orientation"],
        ndims * ndims,
    )?;
    // Of a 4D image's geometry, the spatial part: the first three
    // origin numbers and the upper-left 3×3 of the 4×4 matrix.
    let mut o = [0.0; 3];
    if let Some(origin) = &origin {
        o[..space].copy_from_slice(&origin[..space]);
    }
    let mut axes = Geometry::IDENTITY.direction;
    if let Some(m) = &matrix {
        for (a, axis) in axes.iter_mut().enumerate().take(space) {
            *axis = [0.0; 3];
            axis[..space].copy_from_slice(&m[a * ndims..a * ndims + space]);
        }
    }
    let geometry = geometry_or_warn(o, axes, Space::Lps, &mut warnings);
    Ok(finish(path, dims, spacing, values, ty, format, opts, warnings)?.placed(geometry))
}
