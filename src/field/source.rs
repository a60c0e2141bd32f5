//! Where a volume comes from: a file (or a folder of slices) with the
//! options to read it, or the built-in synthetic field.
//!
//! This is the one description of "the volume to open" that the command
//! line, the explorer and the tests share; it knows nothing of either. The
//! command line parses its flags into a [`VolumeSource`]
//! (`cli::input::InputArgs::source`), the explorer's File menu makes one
//! from a typed path ([`VolumeSource::parse`]), and both call
//! [`VolumeSource::load`].
//!
//! A name spelt `synthetic` (128³), `synthetic:N` (N³), `synthetic:XxYxZ`
//! or `synthetic-noisy[:N]` (noise amplitude 0.05, seed 1) names the
//! built-in field ([`Synthetic`]), unless a file or folder of that name
//! exists.

use std::path::{Path, PathBuf};

use thiserror::Error;

use super::io::{self, ReadError, ReadOptions, ScalarType, Volume};
use super::synthetic::Synthetic;

/// The volume to read and how.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeSource {
    /// A file or folder, read with these options.
    File {
        /// The file or folder.
        path: PathBuf,
        /// How to read it (raw layout, NaN policy, memory limit).
        options: ReadOptions,
    },
    /// The built-in synthetic field.
    Synthetic {
        /// What to generate.
        spec: Synthetic,
        /// How the user spelt it (`synthetic:64`), shown as its name.
        name: String,
    },
}

/// A name that starts like a synthetic spec but is not one.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
#[error("'{0}': expected synthetic:N or synthetic:XxYxZ")]
pub struct SourceError(pub String);

impl Default for VolumeSource {
    /// The built-in synthetic field, 128³: what runs when no input is given.
    fn default() -> Self {
        VolumeSource::Synthetic {
            spec: Synthetic::default(),
            name: "synthetic".into(),
        }
    }
}

impl VolumeSource {
    /// The source `input` names: a synthetic spec, or else a file read with
    /// `options` (the options do not apply to synthetic fields).
    pub fn parse(input: &str, options: ReadOptions) -> Result<Self, SourceError> {
        Ok(match synthetic_spec(input)? {
            Some(spec) => VolumeSource::Synthetic {
                spec,
                name: input.trim().to_string(),
            },
            None => VolumeSource::File {
                path: PathBuf::from(input),
                options,
            },
        })
    }

    /// A file read with default options.
    pub fn file(path: impl Into<PathBuf>) -> Self {
        VolumeSource::File {
            path: path.into(),
            options: ReadOptions::default(),
        }
    }

    /// The file, when the source is one.
    pub fn path(&self) -> Option<&Path> {
        match self {
            VolumeSource::File { path, .. } => Some(path),
            VolumeSource::Synthetic { .. } => None,
        }
    }

    /// What the user asked for, as they spelt it (file path or spec).
    pub fn spelling(&self) -> String {
        match self {
            VolumeSource::File { path, .. } => path.display().to_string(),
            VolumeSource::Synthetic { name, .. } => name.clone(),
        }
    }

    /// Reads the volume (or generates the synthetic field, after the same
    /// size and memory checks as a file).
    pub fn load(&self) -> Result<Volume, ReadError> {
        match self {
            VolumeSource::File { path, options } => io::read_volume(path, options),
            VolumeSource::Synthetic { spec, name } => {
                let path = PathBuf::from(name);
                io::check_volume_size(&path, spec.dims, ScalarType::F32, &ReadOptions::default())?;
                Ok(Volume {
                    field: spec.generate(),
                    path,
                    format: if spec.noise > 0.0 {
                        format!("synthetic (noise {})", spec.noise)
                    } else {
                        "synthetic".into()
                    },
                    scalar_type: ScalarType::F32,
                    warnings: Vec::new(),
                })
            }
        }
    }
}

/// The synthetic field `input` names, if it names one (see the module
/// documentation); an error when it starts like one but does not parse.
pub fn synthetic_spec(input: &str) -> Result<Option<Synthetic>, SourceError> {
    let s = input.trim();
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
    let bad = || SourceError(s.to_string());
    let dims = match rest.strip_prefix(':') {
        None if rest.is_empty() => [128; 3],
        None => return Ok(None),
        Some(spec) => {
            let parts: Vec<usize> = spec
                .split(['x', 'X'])
                .map(|t| t.trim().parse())
                .collect::<Result<_, _>>()
                .map_err(|_| bad())?;
            match parts.as_slice() {
                [n] => [*n; 3],
                [x, y, z] => [*x, *y, *z],
                _ => return Err(bad()),
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

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn synthetic_names_parse() {
        let s = |t: &str| synthetic_spec(t).unwrap();
        assert_eq!(s("synthetic").unwrap().dims, [128; 3]);
        assert_eq!(s("synthetic:16").unwrap().dims, [16; 3]);
        assert_eq!(s("synthetic:4x5x6").unwrap().dims, [4, 5, 6]);
        let noisy = s("synthetic-noisy:8").unwrap();
        assert_eq!((noisy.dims, noisy.noise), ([8; 3], 0.05));
        assert!(s("volume.nrrd").is_none());
        assert!(synthetic_spec("synthetic:abc").is_err());
        let zero = VolumeSource::parse("synthetic:0", ReadOptions::default()).unwrap();
        assert!(zero.load().is_err());
    }

    #[test]
    fn a_source_names_its_file_or_its_spec() {
        let f = VolumeSource::parse("a/b.nrrd", ReadOptions::default()).unwrap();
        assert_eq!(f.path(), Some(Path::new("a/b.nrrd")));
        let s = VolumeSource::parse("synthetic:8", ReadOptions::default()).unwrap();
        assert_eq!((s.path(), s.spelling()), (None, "synthetic:8".to_string()));
        let v = s.load().unwrap();
        assert_eq!(v.field.dims(), [8; 3]);
        assert_eq!(v.format, "synthetic");
    }
}
