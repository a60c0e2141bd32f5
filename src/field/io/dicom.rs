//! DICOM series: a folder of single-frame DICOM files (one slice each, as
//! scanners, PACS exports and ITK's `ImageSeriesWriter` write them), or one
//! DICOM file, read through the dicom-rs crates (`dicom-object`).
//!
//! What is read, per file (DICOM PS3.3 C.7.6.2 Image Plane, C.7.6.3 Image
//! Pixel, C.11.1 Modality LUT):
//!
//! | tag | name | use |
//! |---|---|---|
//! | (0020,000E) | SeriesInstanceUID | every file must share it |
//! | (0028,0010), (0028,0011) | Rows, Columns | slice size, shared |
//! | (0028,0002) | SamplesPerPixel | must be 1 (gray) |
//! | (0028,0100), (0028,0101), (0028,0103) | BitsAllocated, BitsStored, PixelRepresentation | uint8/int8/uint16/int16/uint32/int32; bits above BitsStored are masked (or sign-extended) |
//! | (0028,0008) | NumberOfFrames | must be 1 in a series |
//! | (0020,0032) | ImagePositionPatient | world (LPS) position of the slice's first pixel |
//! | (0020,0037) | ImageOrientationPatient | directions of a row (x) and a column (y) |
//! | (0028,0030) | PixelSpacing | spacing between rows (y), then columns (x) |
//! | (0028,1053), (0028,1052) | RescaleSlope, RescaleIntercept | value = slope · stored + intercept |
//! | (0018,0088), (0018,0050) | SpacingBetweenSlices, SliceThickness | z spacing of a single slice, or when positions are missing |
//! | (0020,0013) | InstanceNumber | slice order when positions are missing |
//!
//! **Order and geometry.** Slices are sorted by their position along the
//! normal `n = row × column` (`ImagePositionPatient · n`), never by file
//! name or instance number, as ITK and 3D Slicer do. Vertex (i, j, k)
//! then lies at `P_0 + i·Δx·row + j·Δy·column + k·step`, where `P_0` is the
//! first slice's position and `step = (P_last − P_0) / (N − 1)`: the z axis
//! follows the slices' positions, so a tilted gantry gives a sheared grid
//! rather than a wrong one. Positions are LPS ([`Space::Lps`]).
//!
//! **Refused, with the reason:** files of more than one series, slices of
//! different sizes, orientations, pixel spacings or pixel types, two slices
//! at one position, gaps (the step between two neighbours differs from the
//! median step by more than 2 %: "missing slices" when the gap is a whole
//! multiple of it), multi-frame files inside a series, colour images, and
//! compressed (encapsulated) transfer syntaxes, JPEG, JPEG-LS, JPEG 2000,
//! RLE and the others: decompress them first (`gdcmconv --raw`,
//! `dcmdjpeg`). Read: implicit and explicit VR little endian, deflated
//! explicit VR little endian, explicit VR big endian.
//!
//! **Values.** When every slice has slope 1 and intercept 0 the stored
//! type is kept. Otherwise values are rescaled: to int16 or int32 when
//! every slice's slope and intercept are integers and the results fit
//! (CT's usual slope 1, intercept −1024), else to float32 (exact for 8 and
//! 16-bit data with one slope). Slices may carry different slopes (PET
//! does): each is rescaled with its own.

use super::{ReadError, ReadOptions, ScalarType, Volume, check_dims, finish, invalid};
use crate::field::{Geometry, Space, Values};
use dicom_dictionary_std::tags;
use dicom_object::{InMemDicomObject, OpenFileOptions};
use std::path::{Path, PathBuf};

/// True when `p` is a file that looks like DICOM: extension `.dcm`, `.dicom`
/// or `.ima`, or the `DICM` magic at byte 128 (files without extension, as
/// scanners name them). `DICOMDIR` index files are not slices.
pub fn is_dicom_file(p: &Path) -> bool {
    if !p.is_file() {
        return false;
    }
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name == "dicomdir" {
        return false;
    }
    if name.ends_with(".dcm") || name.ends_with(".dicom") || name.ends_with(".ima") {
        return true;
    }
    has_magic(p)
}

/// True when the file has the `DICM` magic of a DICOM Part 10 file.
pub fn has_magic(p: &Path) -> bool {
    let Ok(mut f) = std::fs::File::open(p) else {
        return false;
    };
    matches!(super::read_prefix(&mut f, 132), Ok(h) if h.len() == 132 && &h[128..132] == b"DICM")
}

/// The header of one slice: what the series checks and the ordering need.
#[derive(Clone, Debug)]
struct Slice {
    file: PathBuf,
    series: Option<String>,
    transfer_syntax: String,
    rows: usize,
    columns: usize,
    samples: u16,
    bits_allocated: u16,
    bits_stored: u16,
    signed: bool,
    frames: u32,
    position: Option<[f64; 3]>,
    orientation: Option<[f64; 6]>,
    pixel_spacing: Option<[f64; 2]>,
    slope: f64,
    intercept: f64,
    slice_spacing: Option<f64>,
    instance: Option<i64>,
}

impl Slice {
    fn scalar_type(&self) -> Result<ScalarType, ReadError> {
        Ok(match (self.bits_allocated, self.signed) {
            (8, false) => ScalarType::U8,
            (8, true) => ScalarType::I8,
            (16, false) => ScalarType::U16,
            (16, true) => ScalarType::I16,
            (32, false) => ScalarType::U32,
            (32, true) => ScalarType::I32,
            (b, _) => {
                return Err(invalid(
                    &self.file,
                    format!("BitsAllocated {b} is not supported (8, 16 or 32)"),
                ));
            }
        })
    }
}

/// Name of a transfer syntax this reader refuses, for the message.
fn compressed_name(uid: &str) -> Option<&'static str> {
    Some(match uid {
        "1.2.840.10008.1.2.4.50" => "JPEG Baseline",
        "1.2.840.10008.1.2.4.51" => "JPEG Extended",
        "1.2.840.10008.1.2.4.57" | "1.2.840.10008.1.2.4.70" => "JPEG Lossless",
        "1.2.840.10008.1.2.4.80" | "1.2.840.10008.1.2.4.81" => "JPEG-LS",
        "1.2.840.10008.1.2.4.90" | "1.2.840.10008.1.2.4.91" => "JPEG 2000",
        "1.2.840.10008.1.2.4.201" | "1.2.840.10008.1.2.4.202" | "1.2.840.10008.1.2.4.203" => {
            "HTJ2K"
        }
        "1.2.840.10008.1.2.4.100"
        | "1.2.840.10008.1.2.4.101"
        | "1.2.840.10008.1.2.4.102"
        | "1.2.840.10008.1.2.4.103" => "MPEG",
        "1.2.840.10008.1.2.5" => "RLE Lossless",
        _ => return None,
    })
}

/// Transfer syntaxes whose pixel data is read.
const NATIVE: [&str; 4] = [
    "1.2.840.10008.1.2",
    "1.2.840.10008.1.2.1",
    "1.2.840.10008.1.2.1.99",
    "1.2.840.10008.1.2.2",
];

fn open(path: &Path, header_only: bool) -> Result<dicom_object::DefaultDicomObject, ReadError> {
    let opts = OpenFileOptions::new();
    let opts = if header_only {
        opts.read_until(tags::PIXEL_DATA)
    } else {
        opts
    };
    opts.open_file(path).map_err(|e| {
        let mut msg = format!("cannot read as DICOM: {e}");
        let mut src = std::error::Error::source(&e);
        while let Some(s) = src {
            msg.push_str(&format!(": {s}"));
            src = s.source();
        }
        invalid(path, msg.replace(['\n', '\r'], " "))
    })
}

fn text(obj: &InMemDicomObject, tag: dicom_object::Tag) -> Option<String> {
    let e = obj.element_opt(tag).ok()??;
    let s = e.to_str().ok()?;
    let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    (!s.is_empty()).then(|| s.to_owned())
}

fn floats(obj: &InMemDicomObject, tag: dicom_object::Tag) -> Option<Vec<f64>> {
    let e = obj.element_opt(tag).ok()??;
    e.to_multi_float64()
        .ok()
        .filter(|v| v.iter().all(|x| x.is_finite()))
}

fn uint(obj: &InMemDicomObject, tag: dicom_object::Tag) -> Option<u32> {
    let e = obj.element_opt(tag).ok()??;
    e.to_int::<u32>().ok()
}

fn header(path: &Path) -> Result<Slice, ReadError> {
    let obj = open(path, true)?;
    let transfer_syntax = obj
        .meta()
        .transfer_syntax()
        .trim_end_matches(['\0', ' '])
        .to_owned();
    let need = |tag, name: &str| {
        uint(&obj, tag).ok_or_else(|| invalid(path, format!("has no {name}: not an image")))
    };
    let rows = need(tags::ROWS, "Rows")? as usize;
    let columns = need(tags::COLUMNS, "Columns")? as usize;
    let bits_allocated = need(tags::BITS_ALLOCATED, "BitsAllocated")? as u16;
    let arr = |v: Option<Vec<f64>>, n: usize| v.filter(|v| v.len() >= n);
    Ok(Slice {
        file: path.to_owned(),
        series: text(&obj, tags::SERIES_INSTANCE_UID),
        transfer_syntax,
        rows,
        columns,
        samples: uint(&obj, tags::SAMPLES_PER_PIXEL).unwrap_or(1) as u16,
        bits_allocated,
        bits_stored: uint(&obj, tags::BITS_STORED).map_or(bits_allocated, |b| b as u16),
        signed: uint(&obj, tags::PIXEL_REPRESENTATION) == Some(1),
        frames: text(&obj, tags::NUMBER_OF_FRAMES)
            .and_then(|s| s.parse().ok())
            .unwrap_or(1),
        position: arr(floats(&obj, tags::IMAGE_POSITION_PATIENT), 3).map(|v| [v[0], v[1], v[2]]),
        orientation: arr(floats(&obj, tags::IMAGE_ORIENTATION_PATIENT), 6)
            .map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]]),
        pixel_spacing: arr(floats(&obj, tags::PIXEL_SPACING), 2).map(|v| [v[0], v[1]]),
        slope: floats(&obj, tags::RESCALE_SLOPE)
            .and_then(|v| v.first().copied())
            .filter(|&s| s != 0.0)
            .unwrap_or(1.0),
        intercept: floats(&obj, tags::RESCALE_INTERCEPT)
            .and_then(|v| v.first().copied())
            .unwrap_or(0.0),
        slice_spacing: floats(&obj, tags::SPACING_BETWEEN_SLICES)
            .or_else(|| floats(&obj, tags::SLICE_THICKNESS))
            .and_then(|v| v.first().copied())
            .filter(|&s| s > 0.0),
        instance: text(&obj, tags::INSTANCE_NUMBER).and_then(|s| s.parse().ok()),
    })
}

fn check_supported(s: &Slice) -> Result<(), ReadError> {
    if let Some(name) = compressed_name(&s.transfer_syntax) {
        return Err(invalid(
            &s.file,
            format!(
                "DICOM transfer syntax {name} ({}) is compressed, which is not supported; \
                 decompress the series first (gdcmconv --raw, or dcmdjpeg)",
                s.transfer_syntax
            ),
        ));
    }
    if !NATIVE.contains(&s.transfer_syntax.as_str()) {
        return Err(invalid(
            &s.file,
            format!(
                "DICOM transfer syntax {} is not supported (only uncompressed: implicit or \
                 explicit VR little endian, deflated, explicit VR big endian)",
                super::clip(&s.transfer_syntax)
            ),
        ));
    }
    if s.samples != 1 {
        return Err(invalid(
            &s.file,
            format!(
                "has {} samples per pixel (colour): only grayscale DICOM is a scalar volume",
                s.samples
            ),
        ));
    }
    if s.bits_stored == 0 || s.bits_stored > s.bits_allocated {
        return Err(invalid(
            &s.file,
            format!(
                "BitsStored {} does not fit BitsAllocated {}",
                s.bits_stored, s.bits_allocated
            ),
        ));
    }
    s.scalar_type().map(drop)
}

/// Reads one DICOM file: a single slice (a volume of depth 1) or a
/// multi-frame file (its frames as z, spaced by SpacingBetweenSlices).
pub fn read_file(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let s = header(path)?;
    check_supported(&s)?;
    read_slices(path, vec![s], opts)
}

/// Reads the DICOM files of a folder as one series.
pub fn read_series(dir: &Path, files: &[PathBuf], opts: &ReadOptions) -> Result<Volume, ReadError> {
    let mut slices = Vec::with_capacity(files.len());
    for f in files {
        slices.push(header(f)?);
    }
    let first = &slices[0];
    // One series: the UIDs first (the most telling message), then sizes.
    let mut uids: Vec<&str> = slices.iter().filter_map(|s| s.series.as_deref()).collect();
    uids.sort_unstable();
    uids.dedup();
    if uids.len() > 1 {
        let count = |u: &str| {
            slices
                .iter()
                .filter(|s| s.series.as_deref() == Some(u))
                .count()
        };
        let list: Vec<String> = uids
            .iter()
            .take(4)
            .map(|u| format!("{} ({} files)", super::clip(u), count(u)))
            .collect();
        return Err(invalid(
            dir,
            format!(
                "holds {} DICOM series, not one: {}{}; put each series in its own folder",
                uids.len(),
                list.join(", "),
                if uids.len() > 4 { ", …" } else { "" }
            ),
        ));
    }
    for s in &slices {
        check_supported(s)?;
        if s.frames != 1 {
            return Err(invalid(
                &s.file,
                format!(
                    "has {} frames: a series folder takes single-frame files (open a multi-frame file on its own)",
                    s.frames
                ),
            ));
        }
        let differs = |what: &str, a: String, b: String| {
            invalid(
                &s.file,
                format!(
                    "{what} is {a} but {} has {b}: not one series",
                    first.file.file_name().unwrap_or_default().to_string_lossy()
                ),
            )
        };
        if (s.columns, s.rows) != (first.columns, first.rows) {
            return Err(differs(
                "slice size",
                format!("{}x{}", s.columns, s.rows),
                format!("{}x{}", first.columns, first.rows),
            ));
        }
        if (s.bits_allocated, s.bits_stored, s.signed)
            != (first.bits_allocated, first.bits_stored, first.signed)
        {
            return Err(differs(
                "pixel type",
                s.scalar_type()?.name().to_owned(),
                first.scalar_type()?.name().to_owned(),
            ));
        }
        let close =
            |a: &[f64], b: &[f64], tol: f64| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol);
        match (s.orientation, first.orientation) {
            (Some(a), Some(b)) if !close(&a, &b, 1e-4) => {
                return Err(differs(
                    "ImageOrientationPatient",
                    format!("{a:?}"),
                    format!("{b:?}"),
                ));
            }
            (Some(_), None) | (None, Some(_)) => {
                return Err(differs(
                    "ImageOrientationPatient",
                    format!("{:?}", s.orientation),
                    format!("{:?}", first.orientation),
                ));
            }
            _ => {}
        }
        match (s.pixel_spacing, first.pixel_spacing) {
            (Some(a), Some(b)) if !close(&a, &b, 1e-4 * a[0].abs().max(1.0)) => {
                return Err(differs("PixelSpacing", format!("{a:?}"), format!("{b:?}")));
            }
            _ => {}
        }
    }
    read_slices(dir, slices, opts)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn name(p: &Path) -> String {
    p.file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned()
}

/// Orders checked slices, places them, reads their pixels.
fn read_slices(
    path: &Path,
    mut slices: Vec<Slice>,
    opts: &ReadOptions,
) -> Result<Volume, ReadError> {
    let mut warnings = Vec::new();
    let first = slices[0].clone();
    let ty = first.scalar_type()?;
    let (row, col) = match first.orientation {
        Some(o) => ([o[0], o[1], o[2]], [o[3], o[4], o[5]]),
        None => {
            warnings.push("no ImageOrientationPatient: axes taken as x and y".to_owned());
            ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        }
    };
    let normal = cross(row, col);
    let [dy, dx] = first.pixel_spacing.unwrap_or_else(|| {
        warnings.push("no PixelSpacing: spacing 1 in x and y".to_owned());
        [1.0, 1.0]
    });
    let all_positions = slices.iter().all(|s| s.position.is_some());
    let depth = if slices.len() == 1 {
        first.frames.max(1) as usize
    } else {
        slices.len()
    };
    let (origin, z_axis, dz) = if slices.len() > 1 && all_positions {
        let along = |s: &Slice| s.position.map_or(0.0, |p| dot(p, normal));
        slices.sort_by(|a, b| along(a).total_cmp(&along(b)));
        let d: Vec<f64> = slices.iter().map(along).collect();
        let steps: Vec<f64> = d.windows(2).map(|w| w[1] - w[0]).collect();
        let mut sorted = steps.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        for (k, &st) in steps.iter().enumerate() {
            let (a, b) = (&slices[k], &slices[k + 1]);
            if st.abs() < 1e-6_f64.max(median.abs() * 1e-4) {
                return Err(invalid(
                    path,
                    format!(
                        "{} and {} lie at the same position ({:.4} along the normal): \
                         more than one volume in this folder (several series, echoes or time points?)",
                        name(&a.file),
                        name(&b.file),
                        d[k]
                    ),
                ));
            }
            if (st - median).abs() > 0.02 * median {
                let ratio = st / median;
                let missing = ratio.round() - 1.0;
                let message = if missing >= 1.0 && (ratio - ratio.round()).abs() < 0.05 {
                    format!(
                        "missing slices: {:.4} between {} and {} where the other slices are {:.4} apart \
                         (about {missing} missing)",
                        st,
                        name(&a.file),
                        name(&b.file),
                        median
                    )
                } else {
                    format!(
                        "uneven slice spacing: {:.4} between {} and {} where the other slices are {:.4} apart",
                        st,
                        name(&a.file),
                        name(&b.file),
                        median
                    )
                };
                return Err(invalid(path, message));
            }
        }
        let (p0, pn) = (
            slices[0].position.unwrap_or_default(),
            slices[slices.len() - 1].position.unwrap_or_default(),
        );
        let n = (slices.len() - 1) as f64;
        let step: [f64; 3] = std::array::from_fn(|c| (pn[c] - p0[c]) / n);
        let len = dot(step, step).sqrt();
        (p0, step.map(|c| c / len), len)
    } else {
        if slices.len() > 1 {
            warnings.push(
                "not every slice has an ImagePositionPatient: slices ordered by InstanceNumber"
                    .to_owned(),
            );
            slices.sort_by(|a, b| {
                a.instance
                    .cmp(&b.instance)
                    .then_with(|| super::natural_cmp(&name(&a.file), &name(&b.file)))
            });
        }
        let dz = first.slice_spacing.unwrap_or_else(|| {
            if depth > 1 {
                warnings.push("no slice spacing given: spacing 1 in z".to_owned());
            }
            1.0
        });
        (slices[0].position.unwrap_or_default(), normal, dz)
    };
    let dims = [first.columns, first.rows, depth];
    let n = check_dims(path, dims, ty, opts)?;
    let per_slice = first.columns * first.rows;
    let mut values = match ty {
        ScalarType::U8 => Values::U8(Vec::with_capacity(n)),
        ScalarType::I8 => Values::I8(Vec::with_capacity(n)),
        ScalarType::U16 => Values::U16(Vec::with_capacity(n)),
        ScalarType::I16 => Values::I16(Vec::with_capacity(n)),
        ScalarType::U32 => Values::U32(Vec::with_capacity(n)),
        _ => Values::I32(Vec::with_capacity(n)),
    };
    let expect = if slices.len() == 1 { n } else { per_slice };
    for s in &slices {
        append_pixels(s, expect, &mut values)?;
    }
    let rescales: Vec<(f64, f64)> = slices.iter().map(|s| (s.slope, s.intercept)).collect();
    let mut format = format!(
        "DICOM ({} slice{}",
        depth,
        if depth == 1 { "" } else { "s" }
    );
    if rescales.iter().any(|&r| r != (1.0, 0.0)) {
        let (s0, i0) = rescales[0];
        if rescales.iter().all(|&r| r == (s0, i0)) {
            format.push_str(&format!(", rescaled by {s0} + {i0}"));
        } else {
            format.push_str(", rescaled per slice");
        }
        values = rescale(values, &rescales, per_slice, ty.size() <= 2);
    }
    format.push(')');
    let geometry = Geometry::new(origin, [row, col, z_axis], Space::Lps).unwrap_or_else(|e| {
        warnings.push(format!("{e}; placing the grid at the origin, axis-aligned"));
        Geometry {
            space: Space::Lps,
            ..Geometry::IDENTITY
        }
    });
    Ok(finish(path, dims, [dx, dy, dz], values, ty, format, opts, warnings)?.placed(geometry))
}

/// Appends the pixel values of one file (exactly `expect` of them) to
/// `values`, masking or sign-extending bits above BitsStored.
fn append_pixels(s: &Slice, expect: usize, values: &mut Values) -> Result<(), ReadError> {
    use dicom_object::mem::InMemElement;
    let obj = open(&s.file, false)?;
    let element: &InMemElement = obj
        .element(tags::PIXEL_DATA)
        .map_err(|_| invalid(&s.file, "has no PixelData"))?;
    let prim = match element.value() {
        dicom_core::value::Value::Primitive(p) => p,
        _ => {
            return Err(invalid(
                &s.file,
                "PixelData is encapsulated (compressed), which is not supported; decompress the series first",
            ));
        }
    };
    use dicom_core::value::PrimitiveValue as P;
    let bytes_le: Vec<u8>;
    let raw: &[u8] = match prim {
        P::U8(b) => b,
        P::U16(v) => {
            bytes_le = v.iter().flat_map(|x| x.to_le_bytes()).collect();
            &bytes_le
        }
        P::I16(v) => {
            bytes_le = v.iter().flat_map(|x| x.to_le_bytes()).collect();
            &bytes_le
        }
        P::U32(v) => {
            bytes_le = v.iter().flat_map(|x| x.to_le_bytes()).collect();
            &bytes_le
        }
        P::I32(v) => {
            bytes_le = v.iter().flat_map(|x| x.to_le_bytes()).collect();
            &bytes_le
        }
        P::Empty => &[],
        _ => return Err(invalid(&s.file, "PixelData is not made of integers")),
    };
    let size = usize::from(s.bits_allocated / 8);
    let need = expect * size;
    if raw.len() < need {
        return Err(invalid(
            &s.file,
            format!(
                "PixelData is truncated: {} bytes where {}x{}{} {}-bit pixels need {need}",
                raw.len(),
                s.columns,
                s.rows,
                if expect > s.columns * s.rows {
                    format!("x{}", expect / (s.columns * s.rows).max(1))
                } else {
                    String::new()
                },
                s.bits_allocated
            ),
        ));
    }
    let raw = &raw[..need];
    let (bits, stored) = (u32::from(s.bits_allocated), u32::from(s.bits_stored));
    let shift = bits - stored;
    macro_rules! push {
        ($v:expr, $t:ty, $n:expr) => {{
            $v.extend(raw.chunks_exact($n).map(|c| {
                let x = <$t>::from_le_bytes(c.try_into().unwrap_or_default());
                if shift == 0 { x } else { (x << shift) >> shift }
            }))
        }};
    }
    match values {
        Values::U8(v) => push!(v, u8, 1),
        Values::I8(v) => push!(v, i8, 1),
        Values::U16(v) => push!(v, u16, 2),
        Values::I16(v) => push!(v, i16, 2),
        Values::U32(v) => push!(v, u32, 4),
        Values::I32(v) => push!(v, i32, 4),
        _ => return Err(invalid(&s.file, "internal: unexpected value type")),
    }
    Ok(())
}

/// Applies each slice's (slope, intercept): to int16 or int32 when every
/// pair is integral and the results fit, else to float32 for 8 and 16-bit
/// data (`small`) and float64 for 32-bit data.
fn rescale(values: Values, rescales: &[(f64, f64)], per_slice: usize, small: bool) -> Values {
    let n = values.len();
    let slope_at = |i: usize| rescales[(i / per_slice.max(1)).min(rescales.len() - 1)];
    let (lo, hi) = values.range();
    let integral = rescales
        .iter()
        .all(|&(s, c)| s.fract() == 0.0 && c.fract() == 0.0);
    let bound = rescales
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &(s, c)| {
            let (x, y) = (lo * s + c, hi * s + c);
            (a.min(x).min(y), b.max(x).max(y))
        });
    let map = |i: usize| {
        let (s, c) = slope_at(i);
        values.get(i) * s + c
    };
    if integral && bound.0 >= f64::from(i16::MIN) && bound.1 <= f64::from(i16::MAX) {
        Values::I16((0..n).map(|i| map(i) as i16).collect())
    } else if integral && bound.0 >= f64::from(i32::MIN) && bound.1 <= f64::from(i32::MAX) {
        Values::I32((0..n).map(|i| map(i) as i32).collect())
    } else if small {
        Values::F32((0..n).map(|i| map(i) as f32).collect())
    } else {
        Values::F64((0..n).map(map).collect())
    }
}
