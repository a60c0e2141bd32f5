//! NRRD (teem's "nearly raw raster data"): `.nrrd` with the data attached
//! after a blank line, or a `.nhdr` header naming a `data file`.
//!
//! Read: `type` (every NRRD alias), `dimension` 1 to 3 (missing axes have
//! size 1), or 4 with a vector axis first or a time axis last (told by
//! `kinds`, or by a `none` in `space directions`; one component or frame
//! is read: [`super::ReadOptions`]), `sizes`, `encoding` raw / gzip / bzip2 / ascii (also `txt`,
//! `text`, `gz`, `bz2`), `endian`, `spacings` or `space directions` (the
//! spacing of an axis is the norm of its direction vector, its direction
//! in the world the unit vector), `space origin`, `space` (LPS and RAS
//! named, others unnamed; see [`Geometry`]), `byte skip`
//! (-1: the data ends the file; raw only), `line skip`, `data file`
//! (relative to the header's folder). Other fields are ignored; `data file:
//! LIST` and printf-style file lists are refused.
//!
//! As in teem, `line skip` counts lines of the data file before the data and
//! `byte skip` counts bytes after them, in the decompressed stream for
//! compressed encodings.

use super::data::{DataSpec, Encoding, Tail, read_data};
use super::{
    ReadError, ReadOptions, ScalarType, Volume, check_dims, clip, finish, geometry_or_warn,
    invalid, io_error,
};
use crate::field::{Geometry, Space};
use std::io::{BufRead, BufReader, Seek, SeekFrom};
use std::path::Path;

const MAX_HEADER: usize = 1 << 20;

/// Reads a `.nrrd` or `.nhdr` file.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let mut first = true;
    let mut bad_magic = false;
    let (lines, data_offset) = super::read_header_lines(path, MAX_HEADER, |line| {
        if first {
            first = false;
            bad_magic = !is_magic(line);
            return bad_magic;
        }
        line.is_empty()
    })
    .map_err(|e| {
        // A file that is not NRRD at all is best described as such.
        if let ReadError::Invalid { .. } = e {
            match std::fs::File::open(path).and_then(|mut f| super::read_prefix(&mut f, 8)) {
                Ok(head) if !head.starts_with(b"NRRD000") => {
                    invalid(path, "not a NRRD file (does not start with NRRD000x)")
                }
                _ => e,
            }
        } else {
            e
        }
    })?;
    if bad_magic || lines.is_empty() {
        return Err(invalid(
            path,
            "not a NRRD file (does not start with NRRD000x)",
        ));
    }
    let mut h = Header::default();
    for (i, line) in lines.iter().enumerate().skip(1) {
        let line = line.trim_end();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(k) = line.find(":=")
            && !line[..k].contains(": ")
        {
            continue; // key/value pair
        }
        let Some((field, value)) = line.split_once(':') else {
            return Err(invalid(
                path,
                format!(
                    "header line {}: expected 'field: value', found '{}'",
                    i + 1,
                    clip(line)
                ),
            ));
        };
        h.set(path, &field.trim().to_ascii_lowercase(), value.trim())?;
    }
    let attached = data_offset != usize::MAX;
    let (several, count) = if h.dimension == Some(4) {
        h.split_4d(path)?
    } else {
        (super::Several::Frames, 1)
    };
    let (frame, component) = match several {
        super::Several::Frames => (super::choose(path, several, count, opts)?, 0),
        super::Several::Components => (0, super::choose(path, several, count, opts)?),
    };
    let chosen = frame.max(component);
    super::choose(
        path,
        match several {
            super::Several::Frames => super::Several::Components,
            super::Several::Components => super::Several::Frames,
        },
        1,
        opts,
    )?;
    let dimension = h
        .dimension
        .ok_or_else(|| invalid(path, "missing 'dimension'"))?;
    if !(1..=3).contains(&dimension) {
        return Err(invalid(
            path,
            format!(
                "dimension {dimension} is not supported (volumes of dimension 1 to 3, or 4 with a vector or time axis)"
            ),
        ));
    }
    let sizes = h.sizes.ok_or_else(|| invalid(path, "missing 'sizes'"))?;
    if sizes.len() != dimension {
        return Err(invalid(
            path,
            format!(
                "'sizes' has {} numbers but dimension is {dimension}",
                sizes.len()
            ),
        ));
    }
    let mut dims = [1usize; 3];
    dims[..dimension].copy_from_slice(&sizes);
    let ty_name = h.ty.ok_or_else(|| invalid(path, "missing 'type'"))?;
    let ty = ScalarType::parse(&ty_name).ok_or_else(|| {
        invalid(
            path,
            format!("unknown or unsupported type '{}'", clip(&ty_name)),
        )
    })?;
    let enc_name = h
        .encoding
        .ok_or_else(|| invalid(path, "missing 'encoding'"))?;
    let encoding = match enc_name.to_ascii_lowercase().as_str() {
        "raw" => Encoding::Raw,
        "gzip" | "gz" => Encoding::Gzip,
        "bzip2" | "bz2" => Encoding::Bzip2,
        "ascii" | "text" | "txt" => Encoding::Ascii,
        other => {
            return Err(invalid(
                path,
                format!(
                    "unknown or unsupported encoding '{}' (raw, gzip, bzip2, ascii)",
                    clip(other)
                ),
            ));
        }
    };
    let big_endian = match h.endian.as_deref().map(str::to_ascii_lowercase).as_deref() {
        Some("little") => false,
        Some("big") => true,
        Some(other) => {
            return Err(invalid(
                path,
                format!("unknown endian '{}' (little or big)", clip(other)),
            ));
        }
        None if ty.size() > 1 && encoding != Encoding::Ascii => {
            return Err(invalid(
                path,
                format!("missing 'endian' for {} data", ty.name()),
            ));
        }
        None => false,
    };
    let mut spacing = [1.0f64; 3];
    let mut axes = Geometry::IDENTITY.direction;
    if let Some(dirs) = &h.directions {
        if dirs.len() != dimension {
            return Err(invalid(
                path,
                format!(
                    "'space directions' has {} entries but dimension is {dimension}",
                    dirs.len()
                ),
            ));
        }
        for (a, d) in dirs.iter().enumerate() {
            if let Some(v) = d {
                let mut axis = [0.0; 3];
                for (c, x) in axis.iter_mut().zip(v) {
                    *c = *x;
                }
                spacing[a] = v.iter().map(|c| c * c).sum::<f64>().sqrt();
                axes[a] = axis;
            }
        }
    } else if let Some(sp) = &h.spacings {
        if sp.len() != dimension {
            return Err(invalid(
                path,
                format!(
                    "'spacings' has {} numbers but dimension is {dimension}",
                    sp.len()
                ),
            ));
        }
        for (s, v) in spacing.iter_mut().zip(sp) {
            if v.is_finite() {
                *s = *v;
            }
        }
    }
    let voxels = check_dims(path, dims, ty, opts)?;
    // Every frame or component is read, one kept (NRRD's sizes are exact).
    let n = match dims[0].checked_mul(count) {
        Some(x) => check_dims(path, [x, dims[1], dims[2]], ty, opts)?,
        None => return Err(invalid(path, format!("{count} volumes overflow"))),
    };

    // Where the data is.
    let (data_file, mut offset) = match &h.data_file {
        Some(name) => {
            if name == "LIST" || name.contains('%') || name.split_whitespace().count() > 1 {
                return Err(invalid(
                    path,
                    format!(
                        "data file '{}' is a file list, which is not supported",
                        clip(name)
                    ),
                ));
            }
            let dir = path.parent().unwrap_or(Path::new("."));
            (dir.join(name), 0u64)
        }
        None if attached => (path.to_owned(), data_offset as u64),
        None => {
            return Err(invalid(
                path,
                "header has no blank line before data and no 'data file' field",
            ));
        }
    };
    if h.line_skip > 0 {
        offset = skip_lines(&data_file, offset, h.line_skip)?;
    }
    let value_bytes = n as u64 * ty.size() as u64;
    let (offset, skip_decoded) = match (h.byte_skip, encoding) {
        (-1, Encoding::Raw) => {
            let len = std::fs::metadata(&data_file)
                .map_err(|e| io_error(&data_file, e))?
                .len();
            if len < offset + value_bytes {
                return Err(invalid(
                    &data_file,
                    format!(
                        "data truncated: the header promises {value_bytes} bytes at the end of the file but the file has only {}",
                        len.saturating_sub(offset)
                    ),
                ));
            }
            (len - value_bytes, 0)
        }
        (-1, _) => {
            return Err(invalid(
                path,
                "'byte skip: -1' is only allowed with raw encoding",
            ));
        }
        (b, _) if b < -1 => return Err(invalid(path, format!("'byte skip: {b}' is invalid"))),
        (b, Encoding::Raw) => (offset + b as u64, 0),
        (b, _) => (offset, b as u64),
    };
    let spec = DataSpec {
        file: data_file,
        offset,
        skip_decoded,
        encoding,
        ty,
        big_endian,
        count: n,
        tail: Tail::Error,
    };
    let (values, mut warnings) = read_data(path, &spec)?;
    let values = super::select(values, voxels, count, chosen, several);
    let format = format!(
        "NRRD{} ({}{})",
        if attached { "" } else { " detached" },
        encoding.name(),
        super::choice_note(several, chosen, count)
    );
    let mut origin = [0.0; 3];
    for (o, x) in origin.iter_mut().zip(h.origin.iter().flatten()) {
        *o = *x;
    }
    let geometry = if h.origin.is_some() || h.directions.is_some() {
        geometry_or_warn(origin, axes, h.space, &mut warnings)
    } else {
        Geometry {
            space: h.space,
            ..Geometry::IDENTITY
        }
    };
    Ok(finish(path, dims, spacing, values, ty, format, opts, warnings)?.placed(geometry))
}

fn is_magic(line: &str) -> bool {
    line.len() == 8 && line.starts_with("NRRD000") && line.as_bytes()[7].is_ascii_digit()
}

#[derive(Default)]
struct Header {
    dimension: Option<usize>,
    sizes: Option<Vec<usize>>,
    ty: Option<String>,
    encoding: Option<String>,
    endian: Option<String>,
    spacings: Option<Vec<f64>>,
    /// Per axis, its vector in space (length = spacing), or None.
    directions: Option<Vec<Option<Vec<f64>>>>,
    origin: Option<Vec<f64>>,
    space: Space,
    byte_skip: i64,
    line_skip: u64,
    data_file: Option<String>,
    kinds: Option<Vec<String>>,
}

impl Header {
    /// A 4D header made 3D: which axis (0: components, 3: frames) holds
    /// several volumes, and how many, found from `kinds` (the axis that is
    /// not `domain` or `space`), else from `space directions` (the axis
    /// whose direction is `none`). That axis is removed from the sizes,
    /// spacings and directions.
    fn split_4d(&mut self, path: &Path) -> Result<(super::Several, usize), ReadError> {
        let spatial = |k: &str| matches!(k.to_ascii_lowercase().as_str(), "domain" | "space");
        let extra: Vec<usize> = if let Some(kinds) = self.kinds.as_ref().filter(|k| k.len() == 4) {
            (0..4).filter(|&a| !spatial(&kinds[a])).collect()
        } else if let Some(dirs) = self.directions.as_ref().filter(|d| d.len() == 4) {
            (0..4).filter(|&a| dirs[a].is_none()).collect()
        } else {
            Vec::new()
        };
        let axis = match extra[..] {
            [a @ (0 | 3)] => a,
            _ => {
                return Err(invalid(
                    path,
                    "dimension 4: no single non-spatial first or last axis in 'kinds' or \
                     'space directions' (a vector axis first, or a time axis last, is read)",
                ));
            }
        };
        let sizes = self
            .sizes
            .as_mut()
            .filter(|s| s.len() == 4)
            .ok_or_else(|| invalid(path, "'sizes' needs 4 numbers for dimension 4"))?;
        let count = sizes.remove(axis);
        if let Some(d) = self.directions.as_mut().filter(|d| d.len() == 4) {
            d.remove(axis);
        }
        if let Some(sp) = self.spacings.as_mut().filter(|s| s.len() == 4) {
            sp.remove(axis);
        }
        self.dimension = Some(3);
        let what = if axis == 0 {
            super::Several::Components
        } else {
            super::Several::Frames
        };
        Ok((what, count))
    }

    fn set(&mut self, path: &Path, field: &str, value: &str) -> Result<(), ReadError> {
        let bad = |what: &str| {
            invalid(
                path,
                format!("bad '{}': {what} '{}'", clip(field), clip(value)),
            )
        };
        match field {
            "dimension" => self.dimension = Some(value.parse().map_err(|_| bad("not a number"))?),
            "sizes" => {
                self.sizes = Some(super::parse_numbers(value).ok_or_else(|| bad("not sizes"))?)
            }
            "type" => self.ty = Some(value.to_owned()),
            "encoding" => self.encoding = Some(value.to_owned()),
            "endian" => self.endian = Some(value.to_owned()),
            "spacings" => {
                let v = value
                    .split_whitespace()
                    .map(|t| t.parse::<f64>().ok())
                    .collect::<Option<Vec<_>>>()
                    .ok_or_else(|| bad("not numbers"))?;
                self.spacings = Some(v);
            }
            "space directions" => {
                let mut dirs = Vec::new();
                for t in value.split_whitespace() {
                    if t == "none" {
                        dirs.push(None);
                        continue;
                    }
                    dirs.push(Some(vector(t).map_err(&bad)?));
                }
                self.directions = Some(dirs);
            }
            "space origin" => {
                let t: String = value.split_whitespace().collect();
                self.origin = Some(vector(&t).map_err(&bad)?);
            }
            "space" => {
                self.space = match value.trim().to_ascii_lowercase().as_str() {
                    "left-posterior-superior" | "lps" => Space::Lps,
                    "right-anterior-superior" | "ras" => Space::Ras,
                    _ => Space::Unnamed,
                }
            }
            "byte skip" => self.byte_skip = value.parse().map_err(|_| bad("not a number"))?,
            "line skip" => self.line_skip = value.parse().map_err(|_| bad("not a number"))?,
            "data file" | "datafile" => self.data_file = Some(value.to_owned()),
            "kinds" => self.kinds = Some(value.split_whitespace().map(str::to_owned).collect()),
            _ => {} // content, measurement frame, ...: not needed.
        }
        Ok(())
    }
}

/// A NRRD vector `(x,y,z)` (any number of components, at most three).
fn vector(t: &str) -> Result<Vec<f64>, &'static str> {
    let inner = t
        .strip_prefix('(')
        .and_then(|t| t.strip_suffix(')'))
        .ok_or("expected (x,y,z) vectors")?;
    let comps = inner
        .split(',')
        .map(|c| c.trim().parse::<f64>().ok())
        .collect::<Option<Vec<_>>>()
        .ok_or("not numbers")?;
    if comps.is_empty() || comps.len() > 3 {
        return Err("expected vectors of 1 to 3 numbers");
    }
    Ok(comps)
}

/// The offset after `lines` more newlines from `offset` in `file`.
fn skip_lines(file: &Path, offset: u64, lines: u64) -> Result<u64, ReadError> {
    let mut f = std::fs::File::open(file).map_err(|e| io_error(file, e))?;
    f.seek(SeekFrom::Start(offset))
        .map_err(|e| io_error(file, e))?;
    let mut r = BufReader::new(f);
    let mut pos = offset;
    let mut sink = Vec::new();
    for i in 0..lines {
        sink.clear();
        // Lines are bounded by the file; cap each to 1 MiB to stay cheap.
        let k = (&mut r)
            .take(1 << 20)
            .read_until(b'\n', &mut sink)
            .map_err(|e| io_error(file, e))?;
        if k == 0 || sink.last() != Some(&b'\n') {
            return Err(invalid(
                file,
                format!("data truncated: 'line skip: {lines}' but the file ends after {i} lines"),
            ));
        }
        pos += k as u64;
    }
    Ok(pos)
}

use std::io::Read as _;
