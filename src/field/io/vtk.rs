//! VTK legacy files (`.vtk`), `DATASET STRUCTURED_POINTS` only: the first
//! array of `POINT_DATA`, binary (big-endian, as the VTK file format
//! specifies) or ASCII, of any attribute kind: `SCALARS` (1 to 4
//! components), `COLOR_SCALARS`, `VECTORS` and `NORMALS` (3),
//! `TEXTURE_COORDINATES` (1 to 3), `TENSORS` (9), or the first array of a
//! `FIELD` (its own number of components). An array of several components
//! is read with `--component C`, as the other formats' vector data.
//!
//! The header is the lines up to the `LOOKUP_TABLE` line that follows
//! `SCALARS` (required by the spec), up to a `COLOR_SCALARS name 1` line
//! (what `vtkStructuredPointsWriter` writes for uint8 data: binary bytes;
//! in ASCII, floats in [0, 1]), up to the line naming any other attribute,
//! or up to the first array line of a `FIELD`; binary data starts on the
//! next byte.
//! The grid is placed at `ORIGIN`, axis-aligned (the format has no
//! direction), in no named space.
//! Anything after the array (more arrays) is ignored. `DIMENSIONS`,
//! `SPACING` (or the old `ASPECT_RATIO`) and `ORIGIN` may come in any order;
//! keywords are matched without case. `long` and `unsigned_long` are read as
//! 64-bit (what VTK writes on Linux and macOS).

use super::data::{DataSpec, Encoding, Tail, read_data};
use super::{ReadError, ReadOptions, ScalarType, Volume, check_dims, clip, finish, invalid};
use crate::field::Geometry;
use std::path::Path;

const MAX_HEADER: usize = 1 << 20;

/// Reads a legacy `.vtk` file.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let mut after_scalars = false;
    let mut after_field = false;
    let mut index = 0;
    let mut not_vtk = false;
    let (lines, data_offset) = super::read_header_lines(path, MAX_HEADER, |line| {
        index += 1;
        if index == 1 && !line.starts_with("# vtk DataFile") {
            not_vtk = true;
            return true;
        }
        if index <= 2 {
            return false; // the title may hold any text
        }
        let kw = line
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_ascii_uppercase();
        if after_field {
            return true; // the FIELD's first array line: its data follows
        }
        if kw == "SCALARS" {
            after_scalars = true;
            return false;
        }
        if kw == "FIELD" {
            after_field = true;
            return false;
        }
        (after_scalars && kw == "LOOKUP_TABLE")
            || matches!(
                kw.as_str(),
                "COLOR_SCALARS" | "VECTORS" | "NORMALS" | "TENSORS" | "TEXTURE_COORDINATES"
            )
    })?;
    if not_vtk {
        return Err(invalid(
            path,
            "not a VTK legacy file (does not start with '# vtk DataFile')",
        ));
    }
    if data_offset == usize::MAX {
        return Err(invalid(
            path,
            "no point data array ('SCALARS name type' and 'LOOKUP_TABLE', 'COLOR_SCALARS', \
             'VECTORS', 'NORMALS', 'TENSORS', 'TEXTURE_COORDINATES' or 'FIELD')",
        ));
    }
    let mut it = lines
        .iter()
        .skip(2)
        .map(|l| l.trim())
        .filter(|l| !l.is_empty());
    let mode = it.next().unwrap_or("").to_ascii_uppercase();
    let encoding = match mode.as_str() {
        "BINARY" => Encoding::Raw,
        "ASCII" => Encoding::Ascii,
        other => {
            return Err(invalid(
                path,
                format!("line 3 must be ASCII or BINARY, not '{}'", clip(other)),
            ));
        }
    };
    let mut dims: Option<[usize; 3]> = None;
    let mut spacing = [1.0f64; 3];
    let mut origin = [0.0f64; 3];
    let mut point_data: Option<usize> = None;
    let mut scalar_type: Option<ScalarType> = None;
    let mut components = 1usize;
    let mut field_array = false;
    for line in it {
        let mut tok = line.split_whitespace();
        let kw = tok.next().unwrap_or("").to_ascii_uppercase();
        let rest: Vec<&str> = tok.collect();
        let bad = |what: &str| invalid(path, format!("bad {kw} line '{}': {what}", clip(line)));
        if field_array {
            // `arrayName numComponents numTuples dataType`.
            let bad = |what: &str| {
                invalid(
                    path,
                    format!("bad FIELD array line '{}': {what}", clip(line)),
                )
            };
            let [c, tuples, ty] = rest[..] else {
                return Err(bad("expected 'name components tuples type'"));
            };
            components = c
                .parse()
                .ok()
                .filter(|&k: &usize| k >= 1)
                .ok_or_else(|| bad("components must be a positive number"))?;
            let tuples: usize = tuples.parse().map_err(|_| bad("expected a tuple count"))?;
            if Some(tuples) != point_data {
                return Err(bad(&format!(
                    "{tuples} tuples, but POINT_DATA {}",
                    point_data.unwrap_or(0)
                )));
            }
            scalar_type = Some(vtk_type(path, ty)?);
            break;
        }
        match kw.as_str() {
            "DATASET" => {
                let kind = rest
                    .first()
                    .map(|s| s.to_ascii_uppercase())
                    .unwrap_or_default();
                if kind != "STRUCTURED_POINTS" {
                    return Err(invalid(
                        path,
                        format!(
                            "VTK dataset '{}' is not supported (only STRUCTURED_POINTS)",
                            clip(&kind)
                        ),
                    ));
                }
            }
            "DIMENSIONS" => {
                let d: Vec<usize> = parse_all(&rest).ok_or_else(|| bad("expected three sizes"))?;
                let [x, y, z] = d[..] else {
                    return Err(bad("expected three sizes"));
                };
                dims = Some([x, y, z]);
            }
            "SPACING" | "ASPECT_RATIO" => {
                let s: Vec<f64> = parse_all(&rest).ok_or_else(|| bad("expected three numbers"))?;
                let [x, y, z] = s[..] else {
                    return Err(bad("expected three numbers"));
                };
                spacing = [x, y, z];
            }
            "ORIGIN" => {
                let o: Vec<f64> = parse_all(&rest).ok_or_else(|| bad("expected three numbers"))?;
                let [x, y, z] = o[..] else {
                    return Err(bad("expected three numbers"));
                };
                origin = [x, y, z];
            }
            "POINT_DATA" => {
                let [n] = rest[..] else {
                    return Err(bad("expected a count"));
                };
                point_data = Some(n.parse().map_err(|_| bad("expected a count"))?);
            }
            "CELL_DATA" => {
                if point_data.is_none() {
                    return Err(invalid(
                        path,
                        "CELL_DATA before POINT_DATA is not supported",
                    ));
                }
            }
            "SCALARS" => {
                if point_data.is_none() {
                    return Err(invalid(
                        path,
                        "SCALARS before POINT_DATA (cell scalars are not supported)",
                    ));
                }
                let name = rest
                    .get(1)
                    .ok_or_else(|| bad("expected 'SCALARS name type'"))?;
                let ty = vtk_type(path, name)?;
                if let Some(c) = rest.get(2) {
                    components = c
                        .parse()
                        .ok()
                        .filter(|&k: &usize| (1..=4).contains(&k))
                        .ok_or_else(|| bad("SCALARS components must be 1 to 4"))?;
                }
                scalar_type = Some(ty);
            }
            "LOOKUP_TABLE" => {}
            "COLOR_SCALARS" if point_data.is_some() && scalar_type.is_none() => {
                if let Some(c) = rest.get(1) {
                    components = c
                        .parse()
                        .ok()
                        .filter(|&k: &usize| k >= 1)
                        .ok_or_else(|| bad("COLOR_SCALARS needs a number of values"))?;
                }
                scalar_type = Some(match encoding {
                    Encoding::Ascii => ScalarType::F32,
                    _ => ScalarType::U8,
                });
            }
            "VECTORS" | "NORMALS" | "TENSORS" | "TEXTURE_COORDINATES"
                if point_data.is_some() && scalar_type.is_none() =>
            {
                // `VECTORS name type`, `TEXTURE_COORDINATES name dim type`.
                let (k, ty) = match (kw.as_str(), &rest[..]) {
                    ("TEXTURE_COORDINATES", [_, dim, ty]) => (
                        dim.parse()
                            .ok()
                            .filter(|d| (1..=3).contains(d))
                            .ok_or_else(|| bad("the dimension must be 1 to 3"))?,
                        *ty,
                    ),
                    ("TEXTURE_COORDINATES", _) => return Err(bad("expected 'name dim type'")),
                    ("TENSORS", [_, ty]) => (9, *ty),
                    (_, [_, ty]) => (3, *ty),
                    _ => return Err(bad("expected 'name type'")),
                };
                components = k;
                scalar_type = Some(vtk_type(path, ty)?);
            }
            "FIELD" if point_data.is_some() && scalar_type.is_none() => {
                let n: usize = rest
                    .get(1)
                    .and_then(|n| n.parse().ok())
                    .ok_or_else(|| bad("expected 'FIELD name arrays'"))?;
                if n == 0 {
                    return Err(bad("a FIELD of no arrays"));
                }
                field_array = true;
            }
            "FIELD"
            | "VECTORS"
            | "NORMALS"
            | "TENSORS"
            | "TEXTURE_COORDINATES"
            | "COLOR_SCALARS" => {
                return Err(invalid(
                    path,
                    format!("{kw} before POINT_DATA (cell or dataset arrays) is not supported"),
                ));
            }
            other => {
                return Err(invalid(
                    path,
                    format!("unexpected keyword '{}'", clip(other)),
                ));
            }
        }
    }
    let dims = dims.ok_or_else(|| invalid(path, "missing DIMENSIONS"))?;
    let ty = scalar_type.ok_or_else(|| invalid(path, "missing the point data array"))?;
    let n = check_dims(path, dims, ty, opts)?;
    super::choose(path, super::Several::Frames, 1, opts)?;
    let component = super::choose(path, super::Several::Components, components, opts)?;
    // Components are interleaved (the fastest axis): all are read, one kept.
    let stored = match dims[0].checked_mul(components) {
        Some(x) => check_dims(path, [x, dims[1], dims[2]], ty, opts)?,
        None => return Err(invalid(path, format!("{components} components overflow"))),
    };
    if point_data != Some(n) {
        return Err(invalid(
            path,
            format!(
                "POINT_DATA {} does not match DIMENSIONS {dims:?} ({n} points)",
                point_data.unwrap_or(0)
            ),
        ));
    }
    let spec = DataSpec {
        file: path.to_owned(),
        offset: data_offset as u64,
        skip_decoded: 0,
        encoding,
        ty,
        big_endian: true,
        count: stored,
        tail: Tail::Ignore,
    };
    let (values, warnings) = read_data(path, &spec)?;
    let values = super::select(values, n, components, component, super::Several::Components);
    let format = format!(
        "VTK legacy ({}{})",
        if encoding == Encoding::Raw {
            "binary"
        } else {
            "ascii"
        },
        super::choice_note(super::Several::Components, component, components)
    );
    let geometry = Geometry {
        origin,
        ..Geometry::IDENTITY
    };
    if !origin.iter().all(|c| c.is_finite()) {
        return Err(invalid(path, "ORIGIN is not finite"));
    }
    Ok(finish(path, dims, spacing, values, ty, format, opts, warnings)?.placed(geometry))
}

/// The value type a VTK type name stands for.
fn vtk_type(path: &Path, name: &str) -> Result<ScalarType, ReadError> {
    Ok(match name.to_ascii_lowercase().as_str() {
        "unsigned_char" => ScalarType::U8,
        "char" | "signed_char" => ScalarType::I8,
        "unsigned_short" => ScalarType::U16,
        "short" => ScalarType::I16,
        "unsigned_int" => ScalarType::U32,
        "int" => ScalarType::I32,
        "unsigned_long" | "vtktypeuint64" => ScalarType::U64,
        "long" | "vtktypeint64" => ScalarType::I64,
        "float" => ScalarType::F32,
        "double" => ScalarType::F64,
        other => {
            return Err(invalid(
                path,
                format!("unknown or unsupported VTK type '{}'", clip(other)),
            ));
        }
    })
}

fn parse_all<T: std::str::FromStr>(tokens: &[&str]) -> Option<Vec<T>> {
    tokens.iter().map(|t| t.parse().ok()).collect()
}
