//! Command-line options shared by every subcommand that reads a volume:
//! flatten [`InputArgs`] into the subcommand's `Args` and call
//! [`InputArgs::load`].
//!
//! Besides files and folders, the input can name the built-in field
//! ([`crate::field::synthetic::Synthetic`]): `synthetic` (128³),
//! `synthetic:N` (N³), `synthetic:XxYxZ`, and `synthetic-noisy[:N]` (noise
//! amplitude 0.05, seed 1).

use crate::field::io::{self, NanPolicy, RawLayout, ReadOptions, ScalarType, Volume};
use crate::field::synthetic::Synthetic;
use anyhow::{Context, bail};
use std::path::{Path, PathBuf};

/// Byte order of a raw file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Endian {
    /// Least significant byte first (x86, ARM).
    #[default]
    Little,
    /// Most significant byte first.
    Big,
}

/// The volume to read and how.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct InputArgs {
    /// Volume file (.nrrd .nhdr .mha .mhd .vtk .vti .nii .nii.gz .raw), a
    /// folder of PNG/TIFF slices, or `synthetic[:N|:XxYxZ]`,
    /// `synthetic-noisy[:N]` for the built-in field.
    #[arg(value_name = "INPUT", default_value = "synthetic")]
    pub input: String,
    /// Dimensions of a raw file: X,Y,Z (or X,Y for an image).
    #[arg(long, value_name = "X,Y,Z", value_delimiter = ',')]
    pub dims: Option<Vec<usize>>,
    /// Scalar type of a raw file: uint8 int8 uint16 int16 uint32 int32
    /// uint64 int64 float32 float64 (NRRD aliases too).
    #[arg(long = "type", value_name = "T")]
    pub scalar_type: Option<String>,
    /// Byte order of a raw file.
    #[arg(long, value_enum, default_value_t = Endian::Little)]
    pub endian: Endian,
    /// What to do with NaN or infinite values: refuse the file, or replace
    /// them by the smallest or largest finite value.
    #[arg(long, value_enum, default_value_t = NanPolicy::Error)]
    pub nan: NanPolicy,
}

impl Default for InputArgs {
    fn default() -> Self {
        default_input()
    }
}

/// The built-in synthetic field, 128³: what runs when no input is given.
pub fn default_input() -> InputArgs {
    InputArgs {
        input: "synthetic".into(),
        dims: None,
        scalar_type: None,
        endian: Endian::Little,
        nan: NanPolicy::Error,
    }
}

impl InputArgs {
    /// Input args reading `input` with default options.
    pub fn from_input(input: impl Into<String>) -> Self {
        Self {
            input: input.into(),
            ..default_input()
        }
    }

    /// The reader options these arguments ask for.
    pub fn read_options(&self) -> anyhow::Result<ReadOptions> {
        let raw = match (&self.dims, &self.scalar_type) {
            (None, None) => None,
            (Some(d), Some(t)) => {
                let dims = match d.as_slice() {
                    [x, y] => [*x, *y, 1],
                    [x, y, z] => [*x, *y, *z],
                    _ => bail!("--dims needs X,Y,Z or X,Y"),
                };
                if ScalarType::parse(t).is_none() {
                    bail!(
                        "--type '{t}' is unknown (uint8 int8 uint16 int16 uint32 int32 uint64 int64 float32 float64)"
                    );
                }
                Some(RawLayout {
                    dims,
                    scalar_type: t.clone(),
                    big_endian: self.endian == Endian::Big,
                })
            }
            (Some(_), None) => bail!("--dims needs --type too (e.g. --type uint8)"),
            (None, Some(_)) => bail!("--type needs --dims too (e.g. --dims 256,256,128)"),
        };
        Ok(ReadOptions {
            raw,
            nan: self.nan,
            max_memory: None,
        })
    }

    /// The synthetic field this input names, if it names one.
    pub fn synthetic(&self) -> anyhow::Result<Option<Synthetic>> {
        let s = self.input.trim();
        let (noisy, rest) = if let Some(r) = s.strip_prefix("synthetic-noisy") {
            (true, r)
        } else if let Some(r) = s.strip_prefix("synthetic") {
            (false, r)
        } else {
            return Ok(None);
        };
        // A file or folder really named "synthetic..." wins.
        if Path::new(s).exists() {
            return Ok(None);
        }
        let dims = match rest.strip_prefix(':') {
            None if rest.is_empty() => [128; 3],
            None => return Ok(None),
            Some(spec) => {
                let parts: Vec<usize> = spec
                    .split(['x', 'X'])
                    .map(|t| t.trim().parse())
                    .collect::<Result<_, _>>()
                    .with_context(|| format!("'{s}': expected synthetic:N or synthetic:XxYxZ"))?;
                match parts.as_slice() {
                    [n] => [*n; 3],
                    [x, y, z] => [*x, *y, *z],
                    _ => bail!("'{s}': expected synthetic:N or synthetic:XxYxZ"),
                }
            }
        };
        let synth = Synthetic {
            dims,
            ..Synthetic::default()
        };
        Ok(Some(if noisy {
            synth.with_noise(0.05, 1)
        } else {
            synth
        }))
    }

    /// Reads the volume (or generates the synthetic field).
    pub fn load(&self) -> anyhow::Result<Volume> {
        if let Some(synth) = self.synthetic()? {
            let path = PathBuf::from(&self.input);
            // Same checks as a file: size limit and memory, before generating.
            let opts = ReadOptions::default();
            io::check_volume_size(&path, synth.dims, ScalarType::F32, &opts)?;
            let field = synth.generate();
            return Ok(Volume {
                field,
                path,
                format: if synth.noise > 0.0 {
                    format!("synthetic (noise {})", synth.noise)
                } else {
                    "synthetic".into()
                },
                scalar_type: ScalarType::F32,
                warnings: Vec::new(),
            });
        }
        let opts = self.read_options()?;
        Ok(io::read_volume(Path::new(&self.input), &opts)?)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn synthetic_names_parse() {
        let s = |t: &str| InputArgs::from_input(t).synthetic().unwrap();
        assert_eq!(s("synthetic").unwrap().dims, [128; 3]);
        assert_eq!(s("synthetic:16").unwrap().dims, [16; 3]);
        assert_eq!(s("synthetic:4x5x6").unwrap().dims, [4, 5, 6]);
        let noisy = s("synthetic-noisy:8").unwrap();
        assert_eq!((noisy.dims, noisy.noise), ([8; 3], 0.05));
        assert!(s("volume.nrrd").is_none());
        assert!(InputArgs::from_input("synthetic:abc").synthetic().is_err());
        assert!(InputArgs::from_input("synthetic:0").load().is_err());
    }
}
