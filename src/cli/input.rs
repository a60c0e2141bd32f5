//! Command-line options shared by every subcommand that reads a volume:
//! flatten [`InputArgs`] into the subcommand's `Args` and call
//! [`InputArgs::load`].
//!
//! A thin wrapper: the flags become a library [`VolumeSource`] (a file with
//! its [`ReadOptions`], or the built-in field: `synthetic`, `synthetic:N`,
//! `synthetic:XxYxZ`, `synthetic-noisy[:N]`); nothing outside `cli` sees
//! clap.

use crate::field::io::{NanPolicy, RawLayout, ReadOptions, ScalarType, Volume};
use crate::field::source::{self, VolumeSource};
use crate::field::synthetic::Synthetic;
use crate::measure::geometric::Measure;
use anyhow::bail;

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
    /// Volume file (.nrrd .nhdr .mha .mhd .vtk .vti .nii .nii.gz .mgh .mgz
    /// .tif .dcm .raw), a folder of PNG/TIFF slices or of one DICOM series, or `synthetic[:N|:XxYxZ]`,
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
    #[arg(long, value_parser = nan_parser(), default_value_t = NanPolicy::Error)]
    pub nan: NanPolicy,
    /// Which frame of a 4D file (NIfTI time series, MGH frames, 4D NRRD or
    /// MetaImage) to read, from 0.
    #[arg(long, value_name = "T")]
    pub frame: Option<usize>,
    /// Which component of a vector file (MetaImage channels, NRRD vector
    /// axis, VTK/VTI NumberOfComponents, NIfTI dim 5) to read, from 0.
    #[arg(long, value_name = "C")]
    pub component: Option<usize>,
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
        frame: None,
        component: None,
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
            frame: self.frame,
            component: self.component,
        })
    }

    /// The volume source these arguments name (a file with its read
    /// options, or a synthetic spec).
    pub fn source(&self) -> anyhow::Result<VolumeSource> {
        let options = self.read_options()?;
        Ok(VolumeSource::parse(&self.input, options)?)
    }

    /// The synthetic field this input names, if it names one.
    pub fn synthetic(&self) -> anyhow::Result<Option<Synthetic>> {
        Ok(source::synthetic_spec(&self.input)?)
    }

    /// Reads the volume (or generates the synthetic field).
    pub fn load(&self) -> anyhow::Result<Volume> {
        Ok(self.source()?.load()?)
    }
}

/// `--measure`: the measure's names as the command line spells them
/// (`height`, `volume`, `hypervolume`), parsed by [`Measure`]'s `FromStr`.
pub fn measure_parser() -> impl clap::builder::TypedValueParser<Value = Measure> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(Measure::ALL.map(|m| PossibleValue::new(m.name()).help(m.summary())))
        .try_map(|s| s.parse::<Measure>())
}

/// `--nan`: `error`, `min` or `max`, parsed by [`NanPolicy`]'s `FromStr`.
pub fn nan_parser() -> impl clap::builder::TypedValueParser<Value = NanPolicy> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(
        NanPolicy::ALL.map(|n| PossibleValue::new(n.name()).help(n.summary())),
    )
    .try_map(|s| s.parse::<NanPolicy>())
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
