//! VTK XML ImageData (`.vti`): one piece, the point-data array named by
//! `PointData Scalars=` (or the first), in any of the three formats VTK
//! writes:
//!
//! * `ascii`: whitespace-separated numbers;
//! * `binary`: base64 inline, a size header (`header_type` UInt32 or
//!   UInt64) then the data; VTK encodes the header and the data as two
//!   base64 runs, other writers as one: both are accepted;
//! * `appended` with `AppendedData encoding="raw"`: raw bytes after the `_`
//!   mark at the array's `offset`. Large uncompressed appended arrays are
//!   read straight from the file into the typed values;
//! * `appended` with `encoding="base64"` (what `vtkXMLImageDataWriter`
//!   writes by default): as inline binary, from the array's `offset` in
//!   base64 characters.
//!
//! With `compressor="vtkZLibDataCompressor"` the data is a block header
//! (`nblocks, blocksize, lastblocksize, csize...`) then zlib blocks; with
//! `vtkLZ4DataCompressor` LZ4 blocks (lz4_flex), with
//! `vtkLZMADataCompressor` xz streams (lzma-rs).
//!
//! The grid is placed by `Origin` and `Direction` (row-major: column a is
//! the direction of axis a) of `ImageData`, and the extent's first index
//! (see [`Geometry`](crate::field::Geometry)); VTK names no space.
//!
//! The XML is scanned by a small tag reader, not a full XML parser: enough
//! for what VTK and common writers produce.

use super::data::{self, DataError, DataSpec, Encoding, Tail, read_data};
use super::{
    ReadError, ReadOptions, ScalarType, Volume, check_dims, clip, finish, geometry_or_warn,
    invalid, io_error,
};
use crate::field::Space;
use base64::Engine as _;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// A start or end tag.
#[derive(Debug)]
struct Tag {
    name: String,
    attrs: Vec<(String, String)>,
    closing: bool,
    /// Byte offset just after `>`.
    end: usize,
}

impl Tag {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// The next tag at or after `from`, skipping `<?...?>` and comments.
/// `None` when the buffer ends first; `Err` on a malformed tag.
fn next_tag(buf: &[u8], mut from: usize) -> Result<Option<Tag>, String> {
    loop {
        let Some(lt) = buf
            .get(from..)
            .and_then(|b| b.iter().position(|&c| c == b'<'))
        else {
            return Ok(None);
        };
        let start = from + lt;
        let rest = &buf[start..];
        if rest.starts_with(b"<!--") {
            let Some(e) = find(rest, b"-->") else {
                return Ok(None);
            };
            from = start + e + 3;
            continue;
        }
        let Some(gt) = rest.iter().position(|&c| c == b'>') else {
            return Ok(None);
        };
        let end = start + gt + 1;
        if rest.starts_with(b"<?") || rest.starts_with(b"<!") {
            from = end;
            continue;
        }
        let inner = std::str::from_utf8(&rest[1..gt])
            .map_err(|_| format!("tag at byte {start} is not text"))?;
        let inner = inner.strip_suffix('/').unwrap_or(inner);
        let (closing, inner) = match inner.strip_prefix('/') {
            Some(i) => (true, i),
            None => (false, inner),
        };
        let name_len = inner
            .find(|c: char| c.is_whitespace())
            .unwrap_or(inner.len());
        let name = inner[..name_len].to_owned();
        if name.is_empty() {
            return Err(format!("empty tag at byte {start}"));
        }
        let mut attrs = Vec::new();
        let mut s = inner[name_len..].trim_start();
        while !s.is_empty() {
            let eq = s
                .find('=')
                .ok_or_else(|| format!("attribute without value in <{}>", clip(&name)))?;
            let key = s[..eq].trim().to_owned();
            let after = s[eq + 1..].trim_start();
            let quote = after.chars().next().filter(|c| *c == '"' || *c == '\'');
            let Some(q) = quote else {
                return Err(format!(
                    "unquoted attribute '{}' in <{}>",
                    clip(&key),
                    clip(&name)
                ));
            };
            let close = after[1..].find(q).ok_or_else(|| {
                format!(
                    "unterminated attribute '{}' in <{}>",
                    clip(&key),
                    clip(&name)
                )
            })?;
            attrs.push((key, after[1..1 + close].to_owned()));
            s = after[close + 2..].trim_start();
        }
        return Ok(Some(Tag {
            name,
            attrs,
            closing,
            end,
        }));
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// What the scan of the XML found.
struct Layout {
    dims: [usize; 3],
    spacing: [f64; 3],
    /// World position of the extent's first point, and the axis
    /// directions (the columns of VTK's row-major `Direction`).
    origin: [f64; 3],
    axes: [[f64; 3]; 3],
    /// `AppendedData encoding="base64"` (offsets count base64 characters).
    appended_base64: bool,
    big_endian: bool,
    header_u64: bool,
    zlib: bool,
    /// How each compressed block is coded (when `zlib`, i.e. compressed).
    codec: Codec,
    array_type: ScalarType,
    /// `NumberOfComponents`: interleaved, one is read.
    components: usize,
    format: String,
    /// Inline text between `<DataArray>` and `</DataArray>` (ascii, binary).
    inline: Option<(usize, usize)>,
    /// `offset` attribute (appended).
    offset: u64,
    /// Byte just after the `_` of `AppendedData` (appended).
    appended_start: Option<usize>,
}

/// Reads a `.vti` file.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let file_len = std::fs::metadata(path)
        .map_err(|e| io_error(path, e))?
        .len();
    // Scan the first MiB; inline data may need the whole file.
    let mut f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let mut buf = super::read_prefix(&mut f, 1 << 20).map_err(|e| io_error(path, e))?;
    let layout = match scan(path, &buf, buf.len() as u64 == file_len)? {
        Some(l) => l,
        None => {
            f.seek(SeekFrom::Start(0)).map_err(|e| io_error(path, e))?;
            buf.clear();
            f.read_to_end(&mut buf).map_err(|e| io_error(path, e))?;
            scan(path, &buf, true)?.ok_or_else(|| invalid(path, "incomplete VTK XML file"))?
        }
    };
    let ty = layout.array_type;
    super::choose(path, super::Several::Frames, 1, opts)?;
    let comps = layout.components;
    let component = super::choose(path, super::Several::Components, comps, opts)?;
    let voxels = check_dims(path, layout.dims, ty, opts)?;
    // Components are interleaved (the fastest axis): all are read, one kept.
    let d = layout.dims;
    let n = match d[0].checked_mul(comps) {
        Some(x) => check_dims(path, [x, d[1], d[2]], ty, opts)?,
        None => return Err(invalid(path, format!("{comps} components overflow"))),
    };
    let expected = n as u64 * ty.size() as u64;
    let hw = if layout.header_u64 { 8 } else { 4 };
    let err = |e: DataError| data::describe(path, Encoding::Raw, e);
    let (values, warnings, how) = match (
        layout.format.as_str(),
        layout.inline,
        layout.appended_start,
    ) {
        ("ascii", Some((a, b)), _) => {
            let text = std::str::from_utf8(&buf[a..b])
                .map_err(|_| invalid(path, "ascii DataArray is not text"))?;
            let v = data::parse_ascii(text, ty, n, true)
                .map_err(|e| data::describe(path, Encoding::Ascii, e))?;
            (v, Vec::new(), "ascii")
        }
        ("binary", Some((a, b)), _) => {
            let text: Vec<u8> = buf[a..b]
                .iter()
                .copied()
                .filter(|c| !c.is_ascii_whitespace())
                .collect();
            let bytes = decode_inline(
                path,
                &text,
                hw,
                layout.zlib.then_some(layout.codec),
                layout.big_endian,
                expected,
            )?;
            let v = data::values_from_bytes(&bytes, ty, layout.big_endian, n).map_err(err)?;
            (v, Vec::new(), "base64")
        }
        ("appended", _, Some(start)) if layout.appended_base64 => {
            // The array's characters run from its offset to the closing
            // tag ('<' is not a base64 character); the decoder stops
            // after the bytes the header promises.
            let at = start as u64 + layout.offset;
            let mut f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
            f.seek(SeekFrom::Start(at)).map_err(|e| io_error(path, e))?;
            let mut text = Vec::new();
            f.take(file_len.saturating_sub(at))
                .read_to_end(&mut text)
                .map_err(|e| io_error(path, e))?;
            let end = text.iter().position(|&c| c == b'<').unwrap_or(text.len());
            text.truncate(end);
            text.retain(|c| !c.is_ascii_whitespace());
            let bytes = decode_inline(
                path,
                &text,
                hw,
                layout.zlib.then_some(layout.codec),
                layout.big_endian,
                expected,
            )?;
            let v = data::values_from_bytes(&bytes, ty, layout.big_endian, n).map_err(err)?;
            (v, Vec::new(), "appended base64")
        }
        ("appended", _, Some(start)) => {
            let at = start as u64 + layout.offset;
            let mut f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
            f.seek(SeekFrom::Start(at)).map_err(|e| io_error(path, e))?;
            if layout.zlib {
                let bytes = read_zlib_blocks(
                    path,
                    &mut f,
                    (hw, layout.big_endian, layout.codec),
                    expected,
                    file_len.saturating_sub(at),
                )?;
                let v = data::values_from_bytes(&bytes, ty, layout.big_endian, n).map_err(err)?;
                (v, Vec::new(), "appended raw")
            } else {
                let nbytes = read_word(path, &mut f, hw, layout.big_endian)?;
                if nbytes != expected {
                    return Err(invalid(
                        path,
                        format!(
                            "appended array holds {nbytes} bytes but the extent needs {expected}"
                        ),
                    ));
                }
                let spec = DataSpec {
                    file: path.to_owned(),
                    offset: at + hw as u64,
                    skip_decoded: 0,
                    encoding: Encoding::Raw,
                    ty,
                    big_endian: layout.big_endian,
                    count: n,
                    tail: Tail::Ignore,
                };
                let (v, w) = read_data(path, &spec)?;
                (v, w, "appended raw")
            }
        }
        (f, _, _) => {
            return Err(invalid(
                path,
                format!(
                    "DataArray format '{}' is not supported or its data is missing",
                    clip(f)
                ),
            ));
        }
    };
    let values = super::select(values, voxels, comps, component, super::Several::Components);
    let format = format!(
        "VTK XML ImageData ({how}{}{})",
        if layout.zlib {
            format!(", {}", layout.codec.name())
        } else {
            String::new()
        },
        super::choice_note(super::Several::Components, component, comps)
    );
    let mut warnings = warnings;
    let geometry = geometry_or_warn(layout.origin, layout.axes, Space::Unnamed, &mut warnings);
    Ok(finish(
        path,
        layout.dims,
        layout.spacing,
        values,
        ty,
        format,
        opts,
        warnings,
    )?
    .placed(geometry))
}

/// Scans the XML in `buf`. `Ok(None)` when `buf` is only a prefix and the
/// needed parts lie beyond it.
fn scan(path: &Path, buf: &[u8], whole: bool) -> Result<Option<Layout>, ReadError> {
    let bad = |m: String| invalid(path, m);
    let malformed = |m: String| invalid(path, format!("malformed XML: {m}"));
    let mut pos = 0;
    let mut root = None;
    let mut extent = None;
    let mut spacing = [1.0; 3];
    let mut place = Place::default();
    let mut in_point_data = false;
    let mut wanted: Option<String> = None;
    let mut array: Option<Tag> = None;
    let mut inline = None;
    loop {
        let Some(tag) = next_tag(buf, pos).map_err(malformed)? else {
            if whole {
                return Err(bad(match (&root, &array) {
                    (None, _) => "not a VTK XML file (no <VTKFile> element)".into(),
                    (_, None) => "no point-data DataArray found".into(),
                    _ => "file ends before the data".into(),
                }));
            }
            return Ok(None);
        };
        pos = tag.end;
        match (tag.name.as_str(), tag.closing) {
            ("VTKFile", false) => {
                if tag.attr("type") != Some("ImageData") {
                    return Err(bad(format!(
                        "VTK XML type '{}' is not supported (only ImageData)",
                        clip(tag.attr("type").unwrap_or(""))
                    )));
                }
                root = Some(tag);
                continue;
            }
            ("ImageData", false) => {
                let we = tag
                    .attr("WholeExtent")
                    .ok_or_else(|| bad("ImageData without WholeExtent".into()))?;
                extent = Some(parse_extent(path, we)?);
                place.first = parse_extent_start(path, we)?;
                let numbers = |key: &str, want: usize| -> Result<Option<Vec<f64>>, ReadError> {
                    match tag.attr(key) {
                        None => Ok(None),
                        Some(t) => match super::parse_numbers::<f64>(t) {
                            Some(v) if v.len() == want => Ok(Some(v)),
                            _ => Err(bad(format!("bad {key} '{}' ({want} numbers)", clip(t)))),
                        },
                    }
                };
                if let Some(o) = numbers("Origin", 3)? {
                    place.origin = [o[0], o[1], o[2]];
                }
                if let Some(d) = numbers("Direction", 9)? {
                    // Row-major: column a is the direction of axis a.
                    place.axes = std::array::from_fn(|a| [d[a], d[3 + a], d[6 + a]]);
                }
                if let Some(s) = tag.attr("Spacing") {
                    let s: Vec<f64> = super::parse_numbers(s)
                        .ok_or_else(|| bad(format!("bad Spacing '{}'", clip(s))))?;
                    let [x, y, z] = s[..] else {
                        return Err(bad("Spacing needs three numbers".into()));
                    };
                    spacing = [x, y, z];
                }
            }
            ("Piece", false) => {
                if let (Some(p), Some(w)) = (tag.attr("Extent"), extent)
                    && parse_extent(path, p)? != w
                {
                    return Err(bad(
                        "pieces smaller than the WholeExtent are not supported".into()
                    ));
                }
            }
            ("PointData", false) => {
                in_point_data = true;
                wanted = tag.attr("Scalars").map(str::to_owned);
            }
            ("PointData", true) => in_point_data = false,
            ("DataArray", false) if in_point_data && array.is_none() => {
                let name_ok = match &wanted {
                    Some(w) => tag.attr("Name") == Some(w.as_str()),
                    None => true,
                };
                if name_ok {
                    if tag.attr("format") != Some("appended") {
                        // The inline data runs to </DataArray>.
                        let Some(close) = find(&buf[tag.end..], b"</DataArray") else {
                            if whole {
                                return Err(bad("DataArray is not closed".into()));
                            }
                            return Ok(None);
                        };
                        inline = Some((tag.end, tag.end + close));
                        pos = tag.end + close;
                    }
                    array = Some(tag);
                }
            }
            ("AppendedData", false) => {
                let Some(array) = &array else {
                    return Err(bad("no point-data DataArray found".into()));
                };
                place.base64 = match tag.attr("encoding").unwrap_or("raw") {
                    "raw" => false,
                    "base64" => true,
                    o => {
                        return Err(bad(format!(
                            "AppendedData encoding '{}' is not supported (raw or base64)",
                            clip(o)
                        )));
                    }
                };
                let Some(us) = buf[tag.end..].iter().position(|&c| c == b'_') else {
                    return Err(bad("AppendedData has no '_' mark".into()));
                };
                return finish_scan(
                    path,
                    root,
                    extent,
                    (spacing, place),
                    array,
                    inline,
                    Some(tag.end + us + 1),
                )
                .map(Some);
            }
            _ => {}
        }
        if let Some(a) = &array
            && a.attr("format") != Some("appended")
        {
            return finish_scan(path, root, extent, (spacing, place), a, inline, None).map(Some);
        }
    }
}

/// Where the ImageData sits: its origin, direction and first extent index,
/// and how appended data is encoded.
#[derive(Clone, Copy)]
struct Place {
    origin: [f64; 3],
    axes: [[f64; 3]; 3],
    first: [i64; 3],
    base64: bool,
}

impl Default for Place {
    fn default() -> Self {
        Place {
            origin: [0.0; 3],
            axes: crate::field::Geometry::IDENTITY.direction,
            first: [0; 3],
            base64: false,
        }
    }
}

fn finish_scan(
    path: &Path,
    root: Option<Tag>,
    extent: Option<[usize; 3]>,
    (spacing, place): ([f64; 3], Place),
    array: &Tag,
    inline: Option<(usize, usize)>,
    appended_start: Option<usize>,
) -> Result<Layout, ReadError> {
    let root = root.ok_or_else(|| invalid(path, "not a VTK XML file (no <VTKFile> element)"))?;
    let dims = extent.ok_or_else(|| invalid(path, "no ImageData WholeExtent"))?;
    let big_endian = match root.attr("byte_order").unwrap_or("LittleEndian") {
        "LittleEndian" => false,
        "BigEndian" => true,
        o => return Err(invalid(path, format!("unknown byte_order '{}'", clip(o)))),
    };
    let header_u64 = match root.attr("header_type").unwrap_or("UInt32") {
        "UInt32" => false,
        "UInt64" => true,
        o => return Err(invalid(path, format!("unknown header_type '{}'", clip(o)))),
    };
    let (zlib, codec) = match root.attr("compressor") {
        None | Some("") => (false, Codec::Zlib),
        Some("vtkZLibDataCompressor") => (true, Codec::Zlib),
        Some("vtkLZ4DataCompressor") => (true, Codec::Lz4),
        Some("vtkLZMADataCompressor") => (true, Codec::Lzma),
        Some(o) => {
            return Err(invalid(
                path,
                format!(
                    "compressor '{}' is not supported (vtkZLibDataCompressor, \
                     vtkLZ4DataCompressor, vtkLZMADataCompressor)",
                    clip(o)
                ),
            ));
        }
    };
    let t = array.attr("type").unwrap_or("");
    let array_type = match t {
        "Int8" => ScalarType::I8,
        "UInt8" => ScalarType::U8,
        "Int16" => ScalarType::I16,
        "UInt16" => ScalarType::U16,
        "Int32" => ScalarType::I32,
        "UInt32" => ScalarType::U32,
        "Int64" => ScalarType::I64,
        "UInt64" => ScalarType::U64,
        "Float32" => ScalarType::F32,
        "Float64" => ScalarType::F64,
        o => {
            return Err(invalid(
                path,
                format!("unknown or unsupported DataArray type '{}'", clip(o)),
            ));
        }
    };
    let components = match array.attr("NumberOfComponents").map(str::trim) {
        None => 1,
        Some(c) => match c.parse::<usize>() {
            Ok(k) if k >= 1 => k,
            _ => {
                return Err(invalid(
                    path,
                    format!("bad DataArray NumberOfComponents '{}'", clip(c)),
                ));
            }
        },
    };
    let offset = match array.attr("offset") {
        Some(o) => o
            .trim()
            .parse()
            .map_err(|_| invalid(path, format!("bad DataArray offset '{}'", clip(o))))?,
        None => 0,
    };
    // The extent's first point: origin + D · (first × spacing).
    let d = &place.axes;
    let origin = std::array::from_fn(|c| {
        place.origin[c]
            + (0..3)
                .map(|a| place.first[a] as f64 * spacing[a] * d[a][c])
                .sum::<f64>()
    });
    Ok(Layout {
        dims,
        spacing,
        origin,
        axes: place.axes,
        appended_base64: place.base64,
        big_endian,
        header_u64,
        zlib,
        codec,
        array_type,
        components,
        format: array.attr("format").unwrap_or("ascii").to_owned(),
        inline,
        offset,
        appended_start,
    })
}

/// The first index of each axis of an extent `x0 x1 y0 y1 z0 z1`.
fn parse_extent_start(path: &Path, text: &str) -> Result<[i64; 3], ReadError> {
    let e: Vec<i64> = super::parse_numbers(text)
        .ok_or_else(|| invalid(path, format!("bad extent '{}'", clip(text))))?;
    match e[..] {
        [x0, _, y0, _, z0, _] => Ok([x0, y0, z0]),
        _ => Err(invalid(path, format!("bad extent '{}'", clip(text)))),
    }
}

fn parse_extent(path: &Path, text: &str) -> Result<[usize; 3], ReadError> {
    let bad = || invalid(path, format!("bad extent '{}'", clip(text)));
    let e: Vec<i64> = super::parse_numbers(text).ok_or_else(bad)?;
    let [x0, x1, y0, y1, z0, z1] = e[..] else {
        return Err(bad());
    };
    let len = |a: i64, b: i64| -> Result<usize, ReadError> {
        b.checked_sub(a)
            .and_then(|d| d.checked_add(1))
            .filter(|d| *d >= 0)
            .and_then(|d| usize::try_from(d).ok())
            .ok_or_else(bad)
    };
    Ok([len(x0, x1)?, len(y0, y1)?, len(z0, z1)?])
}

fn word(bytes: &[u8], big_endian: bool) -> u64 {
    let mut b = [0u8; 8];
    if bytes.len() == 4 {
        let mut w = [0u8; 4];
        w.copy_from_slice(bytes);
        return if big_endian {
            u32::from_be_bytes(w)
        } else {
            u32::from_le_bytes(w)
        } as u64;
    }
    b.copy_from_slice(&bytes[..8]);
    if big_endian {
        u64::from_be_bytes(b)
    } else {
        u64::from_le_bytes(b)
    }
}

fn read_word(path: &Path, r: &mut impl Read, hw: usize, be: bool) -> Result<u64, ReadError> {
    let mut b = [0u8; 8];
    let got = data::read_full(r, &mut b[..hw]).map_err(|e| io_error(path, e))?;
    if got < hw {
        return Err(invalid(
            path,
            "appended data truncated: the array header is incomplete",
        ));
    }
    Ok(word(&b[..hw], be))
}

fn b64(path: &Path, text: &[u8]) -> Result<Vec<u8>, ReadError> {
    base64::engine::general_purpose::STANDARD
        .decode(text)
        .map_err(|e| invalid(path, format!("corrupt base64 data: {e}")))
}

/// Decodes an inline base64 array to its data bytes (decompressed).
fn decode_inline(
    path: &Path,
    text: &[u8],
    hw: usize,
    codec: Option<Codec>,
    be: bool,
    expected: u64,
) -> Result<Vec<u8>, ReadError> {
    let zlib = codec.is_some();
    let enc_len = |bytes: usize| bytes.div_ceil(3) * 4;
    // The header: one word, or (compressed) three words then the block sizes.
    let first = if zlib { 3 * hw } else { hw };
    let head_text = text
        .get(..enc_len(first))
        .ok_or_else(|| invalid(path, "base64 data truncated: no header"))?;
    let head = b64(path, head_text)?;
    if head.len() < hw {
        return Err(invalid(path, "base64 data truncated: no header"));
    }
    let header_len = if zlib {
        let nblocks = word(&head[..hw], be);
        let len = nblocks
            .checked_mul(hw as u64)
            .and_then(|x| x.checked_add(3 * hw as u64))
            .filter(|&l| enc_len(l as usize) as u64 <= text.len() as u64)
            .ok_or_else(|| {
                invalid(
                    path,
                    format!("compressed header claims {nblocks} blocks, more than the data holds"),
                )
            })?;
        len as usize
    } else {
        hw
    };
    // VTK encodes the header as its own base64 run (padded); others encode
    // header and data as one run.
    let htext = text
        .get(..enc_len(header_len))
        .ok_or_else(|| invalid(path, "base64 data truncated in the header"))?;
    let (header, body) = if header_len % 3 != 0 && htext.ends_with(b"=") {
        let header = b64(path, htext)?;
        (header, b64(path, &text[htext.len()..])?)
    } else {
        let all = b64(path, text)?;
        let body = all.get(header_len..).unwrap_or(&[]).to_vec();
        (all[..header_len.min(all.len())].to_vec(), body)
    };
    if header.len() < header_len {
        return Err(invalid(path, "base64 data truncated in the header"));
    }
    if let Some(codec) = codec {
        let mut r = &header[..];
        let mut body_r = &body[..];
        decode_blocks(
            path,
            (&mut r, &mut body_r),
            hw,
            be,
            codec,
            expected,
            body.len() as u64,
        )
    } else {
        let nbytes = word(&header[..hw], be);
        if nbytes != expected {
            return Err(invalid(
                path,
                format!("binary array holds {nbytes} bytes but the extent needs {expected}"),
            ));
        }
        Ok(body)
    }
}

/// Reads a compressed appended array: the block header, then the blocks.
fn read_zlib_blocks(
    path: &Path,
    f: &mut std::fs::File,
    (hw, be, codec): (usize, bool, Codec),
    expected: u64,
    available: u64,
) -> Result<Vec<u8>, ReadError> {
    let mut reader = std::io::BufReader::new(f);
    let mut header = Vec::new();
    for _ in 0..3 {
        header.extend_from_slice(&read_word(path, &mut reader, hw, be)?.to_le_bytes()[..hw]);
    }
    // Re-encode in the file's order so decode_blocks reads it the same way.
    let nblocks = word_le(&header[..hw]);
    if nblocks.saturating_mul(hw as u64) > available {
        return Err(invalid(
            path,
            format!("compressed header claims {nblocks} blocks, more than the file holds"),
        ));
    }
    for _ in 0..nblocks {
        header.extend_from_slice(&read_word(path, &mut reader, hw, be)?.to_le_bytes()[..hw]);
    }
    let mut h = &header[..];
    decode_blocks(
        path,
        (&mut h, &mut reader),
        hw,
        false,
        codec,
        expected,
        available,
    )
}

fn word_le(b: &[u8]) -> u64 {
    word(b, false)
}

/// How VTK codes each compressed block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Codec {
    /// `vtkZLibDataCompressor`: a zlib stream.
    Zlib,
    /// `vtkLZ4DataCompressor`: an LZ4 block (no frame).
    Lz4,
    /// `vtkLZMADataCompressor`: an xz stream.
    Lzma,
}

impl Codec {
    fn name(self) -> &'static str {
        match self {
            Codec::Zlib => "zlib",
            Codec::Lz4 => "LZ4",
            Codec::Lzma => "LZMA",
        }
    }

    /// Decompresses `comp` into exactly `out`; the error says what went
    /// wrong.
    fn decode(self, comp: &[u8], out: &mut [u8]) -> Result<(), String> {
        let got = match self {
            Codec::Zlib => {
                let mut dec = flate2::read::ZlibDecoder::new(comp);
                data::read_full(&mut dec, out).map_err(|e| e.to_string())?
            }
            Codec::Lz4 => lz4_flex::block::decompress_into(comp, out).map_err(|e| e.to_string())?,
            Codec::Lzma => {
                let mut v = Vec::with_capacity(out.len());
                lzma_rs::xz_decompress(&mut std::io::BufReader::new(comp), &mut v)
                    .map_err(|e| e.to_string())?;
                if v.len() > out.len() {
                    return Err(format!("decompresses to more than {} bytes", out.len()));
                }
                out[..v.len()].copy_from_slice(&v);
                v.len()
            }
        };
        if got < out.len() {
            return Err(format!(
                "decompresses to {got} bytes, expected {}",
                out.len()
            ));
        }
        Ok(())
    }
}

/// Decodes compressed blocks described by a block header read from
/// `header`, their bytes from `body`.
fn decode_blocks(
    path: &Path,
    (header, body): (&mut &[u8], &mut impl Read),
    hw: usize,
    be: bool,
    codec: Codec,
    expected: u64,
    available: u64,
) -> Result<Vec<u8>, ReadError> {
    let mut next = || -> Result<u64, ReadError> {
        if header.len() < hw {
            return Err(invalid(path, "compressed block header truncated"));
        }
        let w = word(&header[..hw], be);
        *header = &header[hw..];
        Ok(w)
    };
    let nblocks = next()?;
    let block = next()?;
    let last = next()?;
    let total = match nblocks {
        0 => Some(0),
        k => (k - 1)
            .checked_mul(block)
            .and_then(|x| x.checked_add(if last == 0 { block } else { last })),
    };
    if total != Some(expected) {
        return Err(invalid(
            path,
            format!(
                "compressed array holds {} bytes but the extent needs {expected}",
                total.map_or("too many".into(), |t| t.to_string())
            ),
        ));
    }
    let mut sizes = Vec::new();
    let mut sum = 0u64;
    for _ in 0..nblocks {
        let s = next()?;
        sum = sum.saturating_add(s);
        sizes.push(s);
    }
    if sum > available {
        return Err(invalid(
            path,
            format!("compressed blocks need {sum} bytes but only {available} are there"),
        ));
    }
    let mut out = vec![0u8; expected as usize];
    let mut at = 0usize;
    for (i, &s) in sizes.iter().enumerate() {
        let want = if i as u64 + 1 == nblocks && last != 0 {
            last
        } else {
            block
        } as usize;
        let mut comp = vec![0u8; s as usize];
        let got = data::read_full(body, &mut comp).map_err(|e| io_error(path, e))?;
        if got < comp.len() {
            return Err(invalid(
                path,
                format!("compressed block {i} truncated: {got} of {s} bytes"),
            ));
        }
        codec.decode(&comp, &mut out[at..at + want]).map_err(|e| {
            invalid(
                path,
                format!("corrupt {} data in block {i}: {e}", codec.name()),
            )
        })?;
        at += want;
    }
    Ok(out)
}
