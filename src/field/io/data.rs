//! The data path every reader shares: from a byte stream (a file region,
//! possibly gzip, bzip2 or zlib compressed, or ASCII numbers) to typed
//! [`Values`], with exact size checks.
//!
//! Values are read straight into their typed `Vec` (viewed as bytes through
//! `bytemuck`), then byte-swapped in place when the file's byte order is not
//! the machine's. Uncompressed data is checked against the file size before
//! the `Vec` is allocated; compressed data fills a `Vec` that grows as the
//! decoder delivers, so a corrupt header cannot make us allocate more than
//! the data actually holds (plus one growth step).

use super::{ReadError, ScalarType, invalid, io_error};
use crate::field::Values;
use std::fs::File;
use std::io::{self, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// How the data bytes are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Plain binary.
    Raw,
    /// Gzip stream (one or more members).
    Gzip,
    /// Bzip2 stream.
    Bzip2,
    /// Zlib stream (MetaImage `.zraw`, VTK XML).
    Zlib,
    /// Whitespace-separated numbers.
    Ascii,
}

impl Encoding {
    /// Lower-case name for messages and format strings.
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Raw => "raw",
            Encoding::Gzip => "gzip",
            Encoding::Bzip2 => "bzip2",
            Encoding::Zlib => "zlib",
            Encoding::Ascii => "ascii",
        }
    }
}

/// What may follow the data in its file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tail {
    /// Nothing: extra bytes are an error.
    Error,
    /// Extra bytes are tolerated with a warning.
    Warn,
    /// Other content follows by design (VTK files).
    Ignore,
}

/// Where the values are and how to decode them.
#[derive(Clone, Debug)]
pub struct DataSpec {
    /// The file holding the data.
    pub file: PathBuf,
    /// Byte offset of the data in the file.
    pub offset: u64,
    /// Bytes to skip after decoding (NRRD byte skip on compressed data,
    /// NIfTI vox_offset inside a .nii.gz).
    pub skip_decoded: u64,
    /// Encoding.
    pub encoding: Encoding,
    /// Scalar type in the file.
    pub ty: ScalarType,
    /// True when multi-byte values are big-endian.
    pub big_endian: bool,
    /// Number of values.
    pub count: usize,
    /// What may follow the data.
    pub tail: Tail,
}

/// Why a stream did not give the promised values (converted to a
/// [`ReadError`] with the file and context by [`read_data`]).
#[derive(Debug)]
pub enum DataError {
    /// The stream ended early.
    Truncated {
        /// Bytes (or numbers, for ASCII) obtained.
        got: u64,
        /// Bytes (or numbers) promised.
        expected: u64,
    },
    /// The stream holds more than promised.
    Extra,
    /// An I/O or decoding error.
    Io(io::Error),
    /// A malformed ASCII number.
    BadNumber(String),
}

/// Reads until `buf` is full or the stream ends; returns the bytes read.
pub fn read_full(r: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// Empty values of the type `ty` is stored as.
fn empty(ty: ScalarType) -> Values {
    match ty {
        ScalarType::U8 => Values::U8(Vec::new()),
        ScalarType::I8 => Values::I8(Vec::new()),
        ScalarType::U16 => Values::U16(Vec::new()),
        ScalarType::I16 => Values::I16(Vec::new()),
        ScalarType::U32 => Values::U32(Vec::new()),
        ScalarType::I32 => Values::I32(Vec::new()),
        ScalarType::F32 => Values::F32(Vec::new()),
        ScalarType::U64 | ScalarType::I64 | ScalarType::F64 => Values::F64(Vec::new()),
    }
}

fn resize(v: &mut Values, n: usize) {
    crate::with_values!(v, x => x.resize(n, Default::default()))
}

fn bytes_mut(v: &mut Values) -> &mut [u8] {
    crate::with_values!(v, x => bytemuck::cast_slice_mut(x.as_mut_slice()))
}

/// Byte-swaps in place when needed and converts 64-bit integer bit patterns
/// (read into an f64 `Vec`) to their f64 values.
fn fix(v: &mut Values, ty: ScalarType, big_endian: bool) {
    let swap = big_endian != cfg!(target_endian = "big") && ty.size() > 1;
    match v {
        Values::U16(x) if swap => x.iter_mut().for_each(|a| *a = a.swap_bytes()),
        Values::I16(x) if swap => x.iter_mut().for_each(|a| *a = a.swap_bytes()),
        Values::U32(x) if swap => x.iter_mut().for_each(|a| *a = a.swap_bytes()),
        Values::I32(x) if swap => x.iter_mut().for_each(|a| *a = a.swap_bytes()),
        Values::F32(x) if swap => x
            .iter_mut()
            .for_each(|a| *a = f32::from_bits(a.to_bits().swap_bytes())),
        Values::F64(x) => {
            let bits = |a: f64| {
                if swap {
                    a.to_bits().swap_bytes()
                } else {
                    a.to_bits()
                }
            };
            match ty {
                ScalarType::I64 => x.iter_mut().for_each(|a| *a = bits(*a) as i64 as f64),
                ScalarType::U64 => x.iter_mut().for_each(|a| *a = bits(*a) as f64),
                _ if swap => x.iter_mut().for_each(|a| *a = f64::from_bits(bits(*a))),
                _ => {}
            }
        }
        _ => {}
    }
}

/// Reads `count` binary values of type `ty` from `r`. With `known` the
/// caller has checked that the stream holds them (an uncompressed file) and
/// the `Vec` is allocated at once; otherwise it grows as data arrives.
/// Does not check for data after the values.
pub fn read_binary(
    r: &mut impl Read,
    ty: ScalarType,
    big_endian: bool,
    count: usize,
    known: bool,
) -> Result<Values, DataError> {
    let size = ty.size();
    let mut v = empty(ty);
    if known {
        // Its pages touched on every core, not one.
        crate::with_values!(&mut v, x => *x = crate::pages::touched(count, Default::default()));
        let buf = bytes_mut(&mut v);
        let got = read_full(r, buf).map_err(DataError::Io)?;
        if got < buf.len() {
            return Err(DataError::Truncated {
                got: got as u64,
                expected: buf.len() as u64,
            });
        }
    } else {
        // Grow by doubling from 16 MiB: a corrupt stream costs at most
        // twice what it actually delivers.
        let first = ((16usize << 20) / size).max(1);
        let mut done = 0usize;
        while done < count {
            let next = done.saturating_mul(2).max(first).min(count);
            resize(&mut v, next);
            let buf = &mut bytes_mut(&mut v)[done * size..next * size];
            let got = read_full(r, buf).map_err(DataError::Io)?;
            if got < buf.len() {
                return Err(DataError::Truncated {
                    got: (done * size + got) as u64,
                    expected: count as u64 * size as u64,
                });
            }
            done = next;
        }
    }
    fix(&mut v, ty, big_endian);
    Ok(v)
}

/// Decodes `count` values from bytes in memory (`bytes` must hold exactly
/// `count * ty.size()` bytes; more or fewer is an error).
pub fn values_from_bytes(
    bytes: &[u8],
    ty: ScalarType,
    big_endian: bool,
    count: usize,
) -> Result<Values, DataError> {
    let expected = count as u64 * ty.size() as u64;
    if (bytes.len() as u64) < expected {
        return Err(DataError::Truncated {
            got: bytes.len() as u64,
            expected,
        });
    }
    if bytes.len() as u64 > expected {
        return Err(DataError::Extra);
    }
    let mut r = bytes;
    read_binary(&mut r, ty, big_endian, count, true)
}

/// Parses `count` whitespace-separated numbers of type `ty` from `text`.
/// With `strict`, anything but whitespace after them is [`DataError::Extra`].
pub fn parse_ascii(
    text: &str,
    ty: ScalarType,
    count: usize,
    strict: bool,
) -> Result<Values, DataError> {
    fn go<T: std::str::FromStr>(
        tokens: &mut std::str::SplitWhitespace<'_>,
        count: usize,
    ) -> Result<Vec<T>, DataError> {
        // The text holds at least two bytes per number, which the caller's
        // size check makes a bound; no allocation beyond what is parsed.
        let mut v = Vec::new();
        for i in 0..count {
            let Some(t) = tokens.next() else {
                return Err(DataError::Truncated {
                    got: i as u64,
                    expected: count as u64,
                });
            };
            v.push(
                t.parse()
                    .map_err(|_| DataError::BadNumber(super::clip(t)))?,
            );
        }
        Ok(v)
    }
    fn ints<T: TryFrom<i128>>(
        tokens: &mut std::str::SplitWhitespace<'_>,
        count: usize,
    ) -> Result<Vec<T>, DataError> {
        let wide: Vec<i128> = go(tokens, count)?;
        wide.into_iter()
            .map(|w| T::try_from(w).map_err(|_| DataError::BadNumber(w.to_string())))
            .collect()
    }
    let mut tokens = text.split_whitespace();
    let t = &mut tokens;
    let v = match ty {
        ScalarType::U8 => Values::U8(ints(t, count)?),
        ScalarType::I8 => Values::I8(ints(t, count)?),
        ScalarType::U16 => Values::U16(ints(t, count)?),
        ScalarType::I16 => Values::I16(ints(t, count)?),
        ScalarType::U32 => Values::U32(ints(t, count)?),
        ScalarType::I32 => Values::I32(ints(t, count)?),
        ScalarType::U64 => Values::F64(
            ints::<u64>(t, count)?
                .into_iter()
                .map(|x| x as f64)
                .collect(),
        ),
        ScalarType::I64 => Values::F64(
            ints::<i64>(t, count)?
                .into_iter()
                .map(|x| x as f64)
                .collect(),
        ),
        ScalarType::F32 => Values::F32(go(t, count)?),
        ScalarType::F64 => Values::F64(go(t, count)?),
    };
    if strict && tokens.next().is_some() {
        return Err(DataError::Extra);
    }
    Ok(v)
}

/// Turns a [`DataError`] into a one-line [`ReadError`] for `file`.
pub fn describe(file: &Path, spec_encoding: Encoding, e: DataError) -> ReadError {
    let what = match spec_encoding {
        Encoding::Raw => "data",
        Encoding::Ascii => "ascii data",
        Encoding::Gzip => "gzip data",
        Encoding::Bzip2 => "bzip2 data",
        Encoding::Zlib => "zlib data",
    };
    match e {
        DataError::Truncated { got, expected } => {
            let unit = if spec_encoding == Encoding::Ascii {
                "numbers"
            } else {
                "bytes"
            };
            let decoded = match spec_encoding {
                Encoding::Raw | Encoding::Ascii => "",
                _ => "decompressed ",
            };
            invalid(
                file,
                format!(
                    "{what} truncated: the header promises {expected} {unit} but the {decoded}data ends after {got}"
                ),
            )
        }
        DataError::Extra => invalid(
            file,
            format!("{what} is longer than the header promises (extra data after the values)"),
        ),
        DataError::BadNumber(t) => invalid(file, format!("{what}: '{t}' is not a valid number")),
        DataError::Io(e) => match spec_encoding {
            Encoding::Raw | Encoding::Ascii => io_error(file, e),
            _ => invalid(file, format!("corrupt {what}: {e}")),
        },
    }
}

/// Reads the values `spec` describes for the volume file `header`, with
/// every size check, returning the values and any warnings. Errors about a
/// separate data file name both files.
pub fn read_data(header: &Path, spec: &DataSpec) -> Result<(Values, Vec<String>), ReadError> {
    read_data_file(spec).map_err(|e| {
        if e.path() == header {
            e
        } else {
            invalid(header, format!("data file {e}"))
        }
    })
}

fn read_data_file(spec: &DataSpec) -> Result<(Values, Vec<String>), ReadError> {
    let path = spec.file.as_path();
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, e))?;
    if meta.is_dir() {
        return Err(invalid(path, "data file is a directory"));
    }
    let file_len = meta.len();
    if spec.offset > file_len {
        return Err(invalid(
            path,
            format!(
                "data truncated: the data should start at byte {} but the file has only {file_len} bytes",
                spec.offset
            ),
        ));
    }
    let mut file = File::open(path).map_err(|e| io_error(path, e))?;
    file.seek(SeekFrom::Start(spec.offset))
        .map_err(|e| io_error(path, e))?;
    let available = file_len - spec.offset;
    let value_bytes = spec.count as u64 * spec.ty.size() as u64;
    let mut warnings = Vec::new();
    let err = |e| describe(path, spec.encoding, e);
    let extra = |warnings: &mut Vec<String>, what: String| -> Result<(), ReadError> {
        match spec.tail {
            Tail::Error => Err(invalid(path, what)),
            Tail::Warn => {
                warnings.push(what);
                Ok(())
            }
            Tail::Ignore => Ok(()),
        }
    };
    let values = match spec.encoding {
        Encoding::Raw => {
            let expected = spec.skip_decoded + value_bytes;
            if available < expected {
                return Err(invalid(
                    path,
                    format!(
                        "data truncated: the header promises {expected} bytes from byte {} but the file has only {available}",
                        spec.offset
                    ),
                ));
            }
            if available > expected {
                extra(
                    &mut warnings,
                    format!(
                        "file is {} bytes longer than the header promises ({expected} data bytes from byte {})",
                        available - expected,
                        spec.offset
                    ),
                )?;
            }
            file.seek(SeekFrom::Current(spec.skip_decoded as i64))
                .map_err(|e| io_error(path, e))?;
            let v = read_binary(&mut file, spec.ty, spec.big_endian, spec.count, true)
                .map_err(|e| match e {
                    // The size was checked: a short read means the file
                    // shrank while we read it.
                    DataError::Truncated { got, expected } => invalid(
                        path,
                        format!(
                            "data truncated while reading (the file changed?): got {got} of {expected} bytes"
                        ),
                    ),
                    e => err(e),
                })?;
            if spec.tail == Tail::Error && available == expected {
                let mut one = [0u8; 1];
                if read_full(&mut file, &mut one).map_err(|e| io_error(path, e))? > 0 {
                    return Err(invalid(
                        path,
                        "file grew while being read (more data than the header promises)",
                    ));
                }
            }
            v
        }
        Encoding::Ascii => {
            // At least one byte per number plus separators: refuse before
            // allocating for a header that promises more than the file holds.
            let min_len = (spec.count as u64).saturating_mul(2).saturating_sub(1);
            if available < min_len {
                return Err(invalid(
                    path,
                    format!(
                        "ascii data truncated: the header promises {} numbers but only {available} bytes follow the header",
                        spec.count
                    ),
                ));
            }
            let mut text = String::new();
            file.read_to_string(&mut text).map_err(|e| match e.kind() {
                io::ErrorKind::InvalidData => invalid(path, "ascii data is not text"),
                _ => io_error(path, e),
            })?;
            parse_ascii(&text, spec.ty, spec.count, spec.tail == Tail::Error).map_err(err)?
        }
        Encoding::Gzip | Encoding::Bzip2 | Encoding::Zlib => {
            let input = BufReader::new(file);
            let mut decoder: Box<dyn Read> = match spec.encoding {
                Encoding::Gzip => Box::new(flate2::read::MultiGzDecoder::new(input)),
                Encoding::Bzip2 => Box::new(bzip2::read::MultiBzDecoder::new(input)),
                _ => Box::new(flate2::read::ZlibDecoder::new(input)),
            };
            let skipped = io::copy(
                &mut decoder.by_ref().take(spec.skip_decoded),
                &mut io::sink(),
            )
            .map_err(|e| err(DataError::Io(e)))?;
            if skipped < spec.skip_decoded {
                return Err(err(DataError::Truncated {
                    got: skipped,
                    expected: spec.skip_decoded + value_bytes,
                }));
            }
            let v = read_binary(&mut decoder, spec.ty, spec.big_endian, spec.count, false)
                .map_err(|e| match e {
                    DataError::Truncated { got, expected } => err(DataError::Truncated {
                        got: got + skipped,
                        expected: expected + skipped,
                    }),
                    e => err(e),
                })?;
            // Read one byte more (never more) to detect extra data.
            let mut one = [0u8; 1];
            match read_full(&mut decoder, &mut one) {
                Ok(0) => {}
                Ok(_) => extra(
                    &mut warnings,
                    format!(
                        "{} data decompresses to more than the {} bytes the header promises",
                        spec.encoding.name(),
                        spec.skip_decoded + value_bytes
                    ),
                )?,
                // Garbage after a complete stream: the values are whole.
                Err(e) => extra(
                    &mut warnings,
                    format!("{} data has trailing garbage: {e}", spec.encoding.name()),
                )?,
            }
            v
        }
    };
    Ok((values, warnings))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A reader that stops early, as a file does when it shrinks while
    /// being read after its size was checked.
    struct Shrinking<'a>(&'a [u8]);
    impl Read for Shrinking<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            let k = buf.len().min(self.0.len()).min(3);
            buf[..k].copy_from_slice(&self.0[..k]);
            self.0 = &self.0[k..];
            Ok(k)
        }
    }

    #[test]
    fn short_stream_is_truncation_not_panic() {
        let data = [1u8, 0, 2, 0, 3];
        for known in [true, false] {
            let r = read_binary(&mut Shrinking(&data), ScalarType::U16, false, 4, known);
            assert!(
                matches!(
                    r,
                    Err(DataError::Truncated {
                        got: 5,
                        expected: 8
                    })
                ),
                "{r:?}"
            );
        }
    }

    #[test]
    fn big_endian_and_64_bit_ints_decode() {
        let bytes = [0x01u8, 0x02, 0xff, 0xfe];
        let v = values_from_bytes(&bytes, ScalarType::I16, true, 2).unwrap();
        assert_eq!(v, Values::I16(vec![0x0102, -2]));
        let mut b = Vec::new();
        b.extend_from_slice(&(-5i64).to_be_bytes());
        b.extend_from_slice(&(1i64 << 40).to_be_bytes());
        let v = values_from_bytes(&b, ScalarType::I64, true, 2).unwrap();
        assert_eq!(v, Values::F64(vec![-5.0, (1u64 << 40) as f64]));
        let v = values_from_bytes(&u64::MAX.to_le_bytes(), ScalarType::U64, false, 1).unwrap();
        assert_eq!(v, Values::F64(vec![u64::MAX as f64]));
    }

    #[test]
    fn ascii_rejects_out_of_range_and_extra() {
        assert!(parse_ascii("1 2 300", ScalarType::U8, 3, true).is_err());
        assert!(matches!(
            parse_ascii("1 2 3 4", ScalarType::U8, 3, true),
            Err(DataError::Extra)
        ));
        assert_eq!(
            parse_ascii("1 -2\n3", ScalarType::I8, 3, true).unwrap(),
            Values::I8(vec![1, -2, 3])
        );
    }
}
