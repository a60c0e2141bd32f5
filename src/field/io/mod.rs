//! Readers for volume files, behind one interface: [`read_volume`].
//!
//! Formats, one module each, all hand-written small header parsers over a
//! shared data path ([`data`]):
//!
//! | format | module | files |
//! |---|---|---|
//! | NRRD | [`nrrd`] | `.nrrd` (attached), `.nhdr` + data file; raw, gzip, bzip2, ascii |
//! | MetaImage | [`metaimage`] | `.mha` (attached), `.mhd` + `.raw`/`.zraw` |
//! | VTK legacy | [`vtk`] | `.vtk` STRUCTURED_POINTS, SCALARS or COLOR_SCALARS, binary (big-endian) or ASCII |
//! | VTK XML | [`vti`] | `.vti` ImageData: ascii, base64 binary, appended raw or base64; zlib, LZ4, LZMA |
//! | NIfTI-1, NIfTI-2 | [`nifti`] | `.nii`, `.nii.gz`, `.hdr` + `.img` |
//! | MGH | [`mgh`] | FreeSurfer `.mgh`, `.mgz` |
//! | raw | [`raw`] | `NAME_XxYxZ_TYPE.raw`, or any file with [`ReadOptions::raw`] |
//! | TIFF | [`stack`] | `.tif`, `.tiff`: one grayscale page, or a multi-page 3D volume |
//! | image stack | [`stack`] | a folder of 8/16-bit gray PNG or grayscale TIFF slices |
//! | DICOM | [`dicom`] | a folder holding one series (one slice per file), or one `.dcm` file; uncompressed transfer syntaxes |
//!
//! What every reader guarantees:
//!
//! * **Errors, never panics**, each a one-line message naming the file and the
//!   problem ([`ReadError`]).
//! * **No allocation beyond the header's promise, and only after checks**:
//!   the dimensions are checked against overflow and [`MAX_VERTICES`], the
//!   memory the engine will need ([`memory_needed`]) against the memory
//!   available, and for uncompressed data the file size against the promise,
//!   before the values are allocated. Compressed data is decompressed into a
//!   buffer that grows as data arrives, capped at the promised byte count
//!   (one byte more is read only to detect extra data).
//! * **One copy**: values are read straight into their typed `Vec` (a
//!   `uint8` file stays one byte per voxel); there is no intermediate byte
//!   buffer for uncompressed data.
//! * **Exact sizes**: data shorter than promised is an error ("truncated");
//!   data longer than promised is an error for raw, NRRD and MetaImage files
//!   (a header that does not describe its file is more likely wrong than
//!   padded), and a warning for NIfTI (some writers pad).
//! * **64-bit integers** (`int64`, `uint64`) are converted to `float64`,
//!   since the engine keeps no 64-bit integer type; values beyond 2^53 lose
//!   precision. [`Volume::scalar_type`] keeps the file's type.
//! * **Geometry**: origin, axis directions and the space (LPS, RAS) come
//!   into the field's [`Geometry`] from every format that has them; an
//!   unusable one (degenerate axes) is a warning and the identity.
//! * **NaN and infinity** are refused with their count and first position,
//!   or replaced by the smallest or largest finite value ([`NanPolicy`]).

pub mod data;
pub mod dicom;
pub mod metaimage;
pub mod mgh;
pub mod nifti;
pub mod nrrd;
pub mod raw;
pub mod stack;
mod tiff;
pub mod vti;
pub mod vtk;

use super::{FieldError, Geometry, MAX_VERTICES, ScalarField, Space, Values, checked_vertex_count};
use std::io::Read;
use std::path::{Path, PathBuf};
use thiserror::Error;

pub(crate) use self::check_volume_size as check_dims;

/// Peak bytes per vertex the engine needs while building the contour tree,
/// on top of the values themselves (vertex order, the sweeps' word per
/// vertex, then the augmented tree). The tree module owns the real figure
/// (`crate::tree`'s module doc): the order (about 1 byte for 8-bit values,
/// else 4) and 8, plus 16 per *candidate node* in the sweeps and about 37
/// at the merge (45 per supernode where the candidates regular in both
/// trees are reduced first; 14, 30 and 37.5 where the candidates' tables
/// are packed: `crate::tree::leafward::packs_tables`): 7-11 on smooth
/// fields and 8-bit brains, 11.1-13.2 on noisy scans (tooth, a noisy
/// 1024³ volume), 21 on white noise. The readers check this a priori figure, that of a noisy scan,
/// before reading: what the engine holds before it knows the candidates
/// (the order and the records, at most 12) is below it. `flexiso info`
/// counts the candidates and quotes `crate::tree::peak_bytes`, and the
/// engine refuses a build that would not fit once it knows them (white
/// noise, say), before the sweeps.
pub const TREE_BYTES_PER_VERTEX: u64 = 14;

/// Bytes per vertex the readers reserve for the engine when checking that a
/// volume fits in memory: [`TREE_BYTES_PER_VERTEX`] plus headroom. A
/// 1024³ uint8 volume is read where 17 GiB are free (it was 21 before the
/// merge's reduction: a noisy one peaks at 14.2).
pub const CHECK_BYTES_PER_VERTEX: u64 = 16;

/// What to do with NaN or infinite values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NanPolicy {
    /// Refuse the file, naming the count and the first position.
    #[default]
    Error,
    /// Replace them by the smallest finite value.
    Min,
    /// Replace them by the largest finite value.
    Max,
}

impl NanPolicy {
    /// Every policy, for menus and help texts.
    pub const ALL: [NanPolicy; 3] = [NanPolicy::Error, NanPolicy::Min, NanPolicy::Max];

    /// Lower-case name, as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            NanPolicy::Error => "error",
            NanPolicy::Min => "min",
            NanPolicy::Max => "max",
        }
    }

    /// One line on what the policy does.
    pub fn summary(self) -> &'static str {
        match self {
            NanPolicy::Error => "Refuse the file, naming the count and the first position",
            NanPolicy::Min => "Replace them by the smallest finite value",
            NanPolicy::Max => "Replace them by the largest finite value",
        }
    }
}

/// A name that is not a NaN policy's.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error("'{0}' is not a NaN policy (error, min, max)")]
pub struct UnknownNanPolicy(pub String);

impl std::str::FromStr for NanPolicy {
    type Err = UnknownNanPolicy;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        NanPolicy::ALL
            .into_iter()
            .find(|n| n.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownNanPolicy(s.to_string()))
    }
}

impl std::fmt::Display for NanPolicy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How to read a headerless raw file.
#[derive(Clone, Debug, PartialEq)]
pub struct RawLayout {
    /// Grid dimensions.
    pub dims: [usize; 3],
    /// Scalar type as NRRD names it: uint8, int16, float32, ... (any name
    /// [`ScalarType::parse`] accepts).
    pub scalar_type: String,
    /// True for big-endian data.
    pub big_endian: bool,
}

/// Options for [`read_volume`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// Layout for raw files whose name does not carry it. When set, the file
    /// is read as raw whatever its name.
    pub raw: Option<RawLayout>,
    /// NaN and infinity policy.
    pub nan: NanPolicy,
    /// Memory (bytes) the volume and its tree may use; `None` means the
    /// `MemAvailable` figure of `/proc/meminfo` (no check where that is
    /// unknown).
    pub max_memory: Option<u64>,
    /// Which 3D frame of a 4D file to read (NIfTI `dim[4]`, MGH frames,
    /// NRRD and MetaImage time axes), from 0 (the command line's
    /// `--frame T`). `None` reads the only frame, and refuses a file with
    /// several, naming the option and the range.
    pub frame: Option<usize>,
    /// Which component of a vector file to read (MetaImage channels, a
    /// NRRD vector axis, VTK `NumberOfComponents`, NIfTI `dim[5]`), from 0
    /// (`--component C`). `None` as for [`ReadOptions::frame`].
    pub component: Option<usize>,
}

/// Frames or components: the two ways a file holds several 3D volumes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Several {
    /// Frames of a 4D file: whole 3D volumes one after the other (time).
    Frames,
    /// Components of a vector file: interleaved, the fastest axis.
    Components,
}

impl Several {
    fn names(self) -> (&'static str, &'static str, &'static str) {
        match self {
            Several::Frames => ("frame", "frames", "--frame T"),
            Several::Components => ("component", "components", "--component C"),
        }
    }
}

/// Which of `count` frames or components to read: the one chosen in
/// `opts` (checked against `count`), or the only one; a file with several
/// and no choice is an error that names the option and the range.
pub(crate) fn choose(
    path: &Path,
    what: Several,
    count: usize,
    opts: &ReadOptions,
) -> Result<usize, ReadError> {
    let chosen = match what {
        Several::Frames => opts.frame,
        Several::Components => opts.component,
    };
    let (one, many, option) = what.names();
    match chosen {
        Some(k) if k < count => Ok(k),
        Some(k) => Err(invalid(
            path,
            format!(
                "{one} {k} does not exist: the file has {count} {} (0 to {})",
                if count == 1 { one } else { many },
                count - 1
            ),
        )),
        None if count == 1 => Ok(0),
        None => Err(invalid(
            path,
            format!(
                "holds {count} {many}: choose one with {option} (0 to {})",
                count - 1
            ),
        )),
    }
}

/// The error for a frame or component chosen on a file that has neither.
pub(crate) fn refuse_choice(path: &Path, opts: &ReadOptions) -> Result<(), ReadError> {
    choose(path, Several::Frames, 1, opts)?;
    choose(path, Several::Components, 1, opts).map(drop)
}

/// The `k`-th of `count` 3D volumes of `n` values each held in `values`:
/// block `k` for frames, every `count`-th value from `k` for components.
pub(crate) fn select(values: Values, n: usize, count: usize, k: usize, what: Several) -> Values {
    if count == 1 {
        return values;
    }
    macro_rules! pick {
        ($v:expr, $variant:ident) => {
            Values::$variant(match what {
                Several::Frames => $v[k * n..(k + 1) * n].to_vec(),
                Several::Components => $v.iter().skip(k).step_by(count).copied().collect(),
            })
        };
    }
    match values {
        Values::U8(v) => pick!(v, U8),
        Values::I8(v) => pick!(v, I8),
        Values::U16(v) => pick!(v, U16),
        Values::I16(v) => pick!(v, I16),
        Values::U32(v) => pick!(v, U32),
        Values::I32(v) => pick!(v, I32),
        Values::F32(v) => pick!(v, F32),
        Values::F64(v) => pick!(v, F64),
    }
}

/// `", frame 3 of 10"` (or component), for a format string; empty for one.
pub(crate) fn choice_note(what: Several, k: usize, count: usize) -> String {
    if count <= 1 {
        return String::new();
    }
    format!(", {} {k} of {count}", what.names().0)
}

/// A volume as read from a file.
#[derive(Clone, Debug)]
pub struct Volume {
    /// The field (values in the file's units, spacing from the header).
    pub field: ScalarField,
    /// The file it came from.
    pub path: PathBuf,
    /// Format name, e.g. "NRRD (gzip)".
    pub format: String,
    /// The scalar type in the file, which may differ from the stored one
    /// (int64 is stored as float64, NIfTI with a slope as float).
    pub scalar_type: ScalarType,
    /// Things the reader tolerated (replaced NaNs, padding after the data,
    /// unusable spacing), for the user to see. Sorted by discovery.
    pub warnings: Vec<String>,
}

impl Volume {
    /// The volume placed in the world by `geometry`.
    pub(crate) fn placed(mut self, geometry: Geometry) -> Self {
        self.field = self.field.with_geometry(geometry);
        self
    }
}

/// The geometry of an origin and three axis vectors (any length) read from
/// a header, or the identity with a warning when they are unusable (not
/// finite, or axes that do not span space).
pub(crate) fn geometry_or_warn(
    origin: [f64; 3],
    axes: [[f64; 3]; 3],
    space: Space,
    warnings: &mut Vec<String>,
) -> Geometry {
    match Geometry::new(origin, axes, space) {
        Ok(g) => g,
        Err(e) => {
            warnings.push(format!("{e}; placing the grid at the origin, axis-aligned"));
            Geometry {
                space,
                ..Geometry::IDENTITY
            }
        }
    }
}

/// Why a volume could not be read.
#[derive(Debug, Error)]
pub enum ReadError {
    /// Any other problem, with the file named.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The file could not be opened or read.
    #[error("{path}: cannot read: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason (part of the message, so not a
        /// `source`: printing the chain would repeat it).
        error: std::io::Error,
    },
    /// The volume would not fit in memory with its contour tree.
    #[error(
        "{path}: {dims:?} {type_name} needs about {} MiB (values and contour tree) but only {} MiB are available",
        needed >> 20,
        available >> 20
    )]
    OutOfMemory {
        /// The file.
        path: PathBuf,
        /// Its dimensions.
        dims: [usize; 3],
        /// Its scalar type.
        type_name: &'static str,
        /// Bytes needed ([`memory_needed`]).
        needed: u64,
        /// Bytes available.
        available: u64,
    },
    /// The values do not make a valid field.
    #[error("{path}: {error}")]
    Field {
        /// The file.
        path: PathBuf,
        /// What is wrong (part of the message, so not a `source`).
        error: FieldError,
    },
}

impl ReadError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            ReadError::Invalid { path, .. }
            | ReadError::Io { path, .. }
            | ReadError::OutOfMemory { path, .. }
            | ReadError::Field { path, .. } => path,
        }
    }
}

/// An [`ReadError::Invalid`] for `path`.
pub(crate) fn invalid(path: &Path, message: impl Into<String>) -> ReadError {
    ReadError::Invalid {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// An [`ReadError::Io`] for `path`.
pub(crate) fn io_error(path: &Path, error: std::io::Error) -> ReadError {
    ReadError::Io {
        path: path.to_owned(),
        error,
    }
}

/// At most 60 characters of user text, control characters escaped, so
/// that messages stay on one line.
pub(crate) fn clip(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars().take(60) {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    if s.chars().count() > 60 {
        out.push('…');
    }
    out
}

/// A scalar type a file can hold. Wider than [`Values`]: 64-bit integers are
/// read and converted to f64.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScalarType {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit.
    I16,
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// Unsigned 64-bit (stored as f64).
    U64,
    /// Signed 64-bit (stored as f64).
    I64,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
}

impl ScalarType {
    /// Bytes per value in the file.
    pub fn size(self) -> usize {
        match self {
            ScalarType::U8 | ScalarType::I8 => 1,
            ScalarType::U16 | ScalarType::I16 => 2,
            ScalarType::U32 | ScalarType::I32 | ScalarType::F32 => 4,
            ScalarType::U64 | ScalarType::I64 | ScalarType::F64 => 8,
        }
    }

    /// The name NRRD gives it (uint8, int16, float32, ...).
    pub fn name(self) -> &'static str {
        match self {
            ScalarType::U8 => "uint8",
            ScalarType::I8 => "int8",
            ScalarType::U16 => "uint16",
            ScalarType::I16 => "int16",
            ScalarType::U32 => "uint32",
            ScalarType::I32 => "int32",
            ScalarType::U64 => "uint64",
            ScalarType::I64 => "int64",
            ScalarType::F32 => "float32",
            ScalarType::F64 => "float64",
        }
    }

    /// Reads a type name: the canonical names above, every NRRD alias
    /// ("unsigned char", "short", "ushort", "long long", "float", "double",
    /// "uint8_t", ...), and "float32"/"float64". Case-insensitive.
    pub fn parse(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_lowercase();
        let n = n.split_whitespace().collect::<Vec<_>>().join(" ");
        Some(match n.as_str() {
            "uint8" | "uint8_t" | "uchar" | "unsigned char" | "u8" => ScalarType::U8,
            "int8" | "int8_t" | "signed char" | "i8" => ScalarType::I8,
            "uint16" | "uint16_t" | "ushort" | "unsigned short" | "unsigned short int" | "u16" => {
                ScalarType::U16
            }
            "int16" | "int16_t" | "short" | "short int" | "signed short" | "signed short int"
            | "i16" => ScalarType::I16,
            "uint32" | "uint32_t" | "uint" | "unsigned int" | "u32" => ScalarType::U32,
            "int32" | "int32_t" | "int" | "signed int" | "i32" => ScalarType::I32,
            "uint64"
            | "uint64_t"
            | "ulonglong"
            | "unsigned long long"
            | "unsigned long long int"
            | "u64" => ScalarType::U64,
            "int64"
            | "int64_t"
            | "longlong"
            | "long long"
            | "long long int"
            | "signed long long"
            | "signed long long int"
            | "i64" => ScalarType::I64,
            "float" | "float32" | "f32" | "single" => ScalarType::F32,
            "double" | "float64" | "f64" => ScalarType::F64,
            _ => return None,
        })
    }

    /// Bytes per value once in memory (64-bit integers become f64).
    pub fn stored_size(self) -> usize {
        self.size()
    }

    /// True for the float types.
    pub fn is_float(self) -> bool {
        matches!(self, ScalarType::F32 | ScalarType::F64)
    }
}

/// Bytes the engine needs for a volume of `vertices` values of
/// `bytes_per_value` each: the values plus [`CHECK_BYTES_PER_VERTEX`].
pub fn memory_needed(vertices: usize, bytes_per_value: usize) -> u64 {
    (vertices as u64).saturating_mul(bytes_per_value as u64 + CHECK_BYTES_PER_VERTEX)
}

/// `MemAvailable` of `/proc/meminfo` in bytes, if known.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// Checks `dims` (overflow, [`MAX_VERTICES`], and the memory the values
/// and the contour tree will need against [`ReadOptions::max_memory`] or
/// [`available_memory`]) before anything is allocated; returns the vertex
/// count.
pub fn check_volume_size(
    path: &Path,
    dims: [usize; 3],
    ty: ScalarType,
    opts: &ReadOptions,
) -> Result<usize, ReadError> {
    let n = checked_vertex_count(dims).map_err(|error| ReadError::Field {
        path: path.to_owned(),
        error,
    })?;
    debug_assert!(n <= MAX_VERTICES);
    let needed = memory_needed(n, ty.stored_size());
    if let Some(available) = opts.max_memory.or_else(available_memory)
        && needed > available
    {
        return Err(ReadError::OutOfMemory {
            path: path.to_owned(),
            dims,
            type_name: ty.name(),
            needed,
            available,
        });
    }
    Ok(n)
}

/// Reads a volume file, choosing the reader by extension and content:
/// a folder is an image stack; with [`ReadOptions::raw`] any file is raw;
/// otherwise the extension decides, and for unknown extensions the first
/// bytes do.
pub fn read_volume(path: &Path, opts: &ReadOptions) -> Result<Volume, ReadError> {
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, e))?;
    if meta.is_dir() {
        refuse_choice(path, opts)?;
        return stack::read(path, opts);
    }
    if let Some(layout) = &opts.raw {
        refuse_choice(path, opts)?;
        return raw::read(path, layout, opts);
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let ext = |e: &str| name.ends_with(e);
    if ext(".nrrd") || ext(".nhdr") {
        return nrrd::read(path, opts);
    }
    if ext(".mha") || ext(".mhd") {
        return metaimage::read(path, opts);
    }
    if ext(".vtk") {
        return vtk::read(path, opts);
    }
    if ext(".vti") {
        return vti::read(path, opts);
    }
    if ext(".nii") || ext(".nii.gz") || ext(".hdr") {
        return nifti::read(path, opts);
    }
    if ext(".raw") {
        refuse_choice(path, opts)?;
        return raw::read_by_name(path, opts);
    }
    if ext(".mgh") || ext(".mgz") {
        return mgh::read(path, opts);
    }
    if ext(".dcm") || ext(".dicom") || ext(".ima") {
        refuse_choice(path, opts)?;
        return dicom::read_file(path, opts);
    }
    if ext(".png") || ext(".tif") || ext(".tiff") {
        refuse_choice(path, opts)?;
        return stack::read_single(path, opts);
    }
    // Unknown extension: sniff.
    let mut head = [0u8; 512];
    let got = std::fs::File::open(path)
        .and_then(|mut f| data::read_full(&mut f, &mut head))
        .map_err(|e| io_error(path, e))?;
    let head = &head[..got];
    if head.starts_with(b"NRRD000") {
        return nrrd::read(path, opts);
    }
    if head.starts_with(b"# vtk DataFile") {
        return vtk::read(path, opts);
    }
    if head.starts_with(b"<?xml") || head.starts_with(b"<VTKFile") {
        return vti::read(path, opts);
    }
    if head.len() >= 132 && &head[128..132] == b"DICM" {
        refuse_choice(path, opts)?;
        return dicom::read_file(path, opts);
    }
    if nifti::sniff(head) {
        return nifti::read(path, opts);
    }
    let text = String::from_utf8_lossy(head);
    if text.starts_with("ObjectType") || text.starts_with("NDims") {
        return metaimage::read(path, opts);
    }
    Err(invalid(
        path,
        "unknown volume format (expected .nrrd, .nhdr, .mha, .mhd, .vtk, .vti, .nii, .nii.gz, .mgh, .mgz, .tif, .dcm, \
         NAME_XxYxZ_TYPE.raw, or a folder of PNG/TIFF slices or of one DICOM series; for other raw files give --dims and --type)",
    ))
}

/// Turns decoded values into a [`Volume`]: applies the NaN policy, makes
/// unusable spacings 1 (with a warning), and builds the field.
#[allow(clippy::too_many_arguments)] // one call per reader, all named
pub(crate) fn finish(
    path: &Path,
    dims: [usize; 3],
    spacing: [f64; 3],
    mut values: Values,
    scalar_type: ScalarType,
    format: String,
    opts: &ReadOptions,
    mut warnings: Vec<String>,
) -> Result<Volume, ReadError> {
    let mut sp = spacing;
    for s in &mut sp {
        *s = s.abs();
        if !(s.is_finite() && *s > 0.0) {
            *s = 1.0;
        }
    }
    if sp != spacing.map(f64::abs) {
        warnings.push(format!("spacing {spacing:?} is unusable; using {sp:?}"));
    }
    // Under `NanPolicy::Error` the field itself reports count and position
    // (one scan of the values, not two).
    if opts.nan != NanPolicy::Error
        && let Some((count, first)) = values.non_finite()
    {
        let Some(fill) = finite_extreme(&values, opts.nan == NanPolicy::Max) else {
            return Err(invalid(path, "every value is NaN or infinite"));
        };
        replace_non_finite(&mut values, fill);
        let [x, y] = [dims[0], dims[1]];
        warnings.push(format!(
            "{count} NaN or infinite values (first at x={} y={} z={}) replaced by {fill}",
            first % x,
            first / x % y,
            first / (x * y)
        ));
    }
    let field = ScalarField::with_spacing(dims, sp, values).map_err(|error| ReadError::Field {
        path: path.to_owned(),
        error,
    })?;
    Ok(Volume {
        field,
        path: path.to_owned(),
        format,
        scalar_type,
        warnings,
    })
}

/// Smallest (or largest) finite value, if any.
fn finite_extreme(values: &Values, max: bool) -> Option<f64> {
    let mut best: Option<f64> = None;
    for i in 0..values.len() {
        let v = values.get(i);
        if v.is_finite() {
            best = Some(match best {
                None => v,
                Some(b) if max => b.max(v),
                Some(b) => b.min(v),
            });
        }
    }
    best
}

fn replace_non_finite(values: &mut Values, fill: f64) {
    match values {
        Values::F32(v) => v
            .iter_mut()
            .filter(|x| !x.is_finite())
            .for_each(|x| *x = fill as f32),
        Values::F64(v) => v
            .iter_mut()
            .filter(|x| !x.is_finite())
            .for_each(|x| *x = fill),
        _ => {}
    }
}

/// Reads the text header at the start of `path`: at most `max` bytes, split
/// into lines (`\n` or `\r\n`) until `is_end` says a line ends the header.
/// Returns the lines (the end line included) and the byte offset just after
/// the end line. When no end line is found the whole file must be header
/// (detached headers), and it must fit in `max` bytes.
pub(crate) fn read_header_lines(
    path: &Path,
    max: usize,
    mut is_end: impl FnMut(&str) -> bool,
) -> Result<(Vec<String>, usize), ReadError> {
    let mut file = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let mut buf = vec![0u8; max];
    let got = data::read_full(&mut file, &mut buf).map_err(|e| io_error(path, e))?;
    buf.truncate(got);
    let mut lines = Vec::new();
    let mut pos = 0;
    while pos < buf.len() {
        let Some(nl) = buf[pos..].iter().position(|&b| b == b'\n') else {
            if got == max {
                return Err(invalid(
                    path,
                    format!("header does not end within its first {max} bytes"),
                ));
            }
            // Last line without newline: fine for a detached header.
            let line = header_line(path, &buf[pos..], lines.len())?;
            let end = is_end(&line);
            lines.push(line);
            return Ok((lines, if end { buf.len() } else { usize::MAX }));
        };
        let line = header_line(path, &buf[pos..pos + nl], lines.len())?;
        pos += nl + 1;
        let end = is_end(&line);
        lines.push(line);
        if end {
            return Ok((lines, pos));
        }
    }
    if got == max {
        return Err(invalid(
            path,
            format!("header does not end within its first {max} bytes"),
        ));
    }
    Ok((lines, usize::MAX))
}

fn header_line(path: &Path, bytes: &[u8], index: usize) -> Result<String, ReadError> {
    let bytes = bytes.strip_suffix(b"\r").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(s) if !s.contains('\0') => Ok(s.to_owned()),
        _ => Err(invalid(
            path,
            format!(
                "header line {} is not text (binary garbage, or data where the header should end)",
                index + 1
            ),
        )),
    }
}

/// Parses `n` whitespace-separated numbers, as in `"64 64 64"`.
pub(crate) fn parse_numbers<T: std::str::FromStr>(text: &str) -> Option<Vec<T>> {
    text.split_whitespace().map(|t| t.parse().ok()).collect()
}

/// Natural-order comparison: digit runs compare by value, so `slice2`
/// comes before `slice10`.
pub fn natural_cmp(a: &str, b: &str) -> std::cmp::Ordering {
    use std::cmp::Ordering;
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, _) => return Ordering::Less,
            (_, None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let da = a.iter().take_while(|c| c.is_ascii_digit()).count();
                let db = b.iter().take_while(|c| c.is_ascii_digit()).count();
                let (na, nb) = (&a[..da], &b[..db]);
                // Compare by value: strip leading zeros, then length, then digits.
                let ta = trim_zeros(na);
                let tb = trim_zeros(nb);
                let ord = ta.len().cmp(&tb.len()).then(ta.cmp(tb)).then(da.cmp(&db));
                if ord != Ordering::Equal {
                    return ord;
                }
                a = &a[da..];
                b = &b[db..];
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(y);
                }
                a = &a[1..];
                b = &b[1..];
            }
        }
    }
}

fn trim_zeros(d: &[u8]) -> &[u8] {
    let k = d.iter().take_while(|&&c| c == b'0').count();
    &d[k..]
}

/// Reads up to `len` bytes of `r` (for header sniffing).
pub(crate) fn read_prefix(r: &mut impl Read, len: usize) -> std::io::Result<Vec<u8>> {
    let mut buf = vec![0u8; len];
    let got = data::read_full(r, &mut buf)?;
    buf.truncate(got);
    Ok(buf)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_puts_slice2_before_slice10() {
        let mut names = vec!["slice10.png", "slice2.png", "slice1.png", "slice02b.png"];
        names.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            names,
            ["slice1.png", "slice2.png", "slice02b.png", "slice10.png"]
        );
    }

    #[test]
    fn type_aliases_parse() {
        for (name, ty) in [
            ("unsigned char", ScalarType::U8),
            ("short", ScalarType::I16),
            ("ushort", ScalarType::U16),
            ("float", ScalarType::F32),
            ("double", ScalarType::F64),
            ("int64", ScalarType::I64),
            ("unsigned  long long int", ScalarType::U64),
            ("signed char", ScalarType::I8),
        ] {
            assert_eq!(ScalarType::parse(name), Some(ty), "{name}");
        }
        assert_eq!(ScalarType::parse("block"), None);
    }
}
