//! DICOM series folders: the CT-like series SimpleITK writes
//! (`formats/real-tools/neghip_dicom`, skipped when the data folder is
//! absent) read as neghip's values rescaled, placed where SimpleITK places
//! them; series the tests write (through dicom-rs) ordered by position
//! whatever the file names, rescaled per slice, placed by a rotated
//! orientation; and clear errors for mixed series, missing slices, two
//! slices at one position, and compressed transfer syntaxes.
#![allow(clippy::unwrap_used)]

mod common;
use common::formats::*;

use dicom_core::{DataElement, PrimitiveValue, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
use flexiso::field::{Space, Values};
use std::path::{Path, PathBuf};

const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
const CT_IMAGE: &str = "1.2.840.10008.5.1.4.1.1.2";

/// One slice to write.
#[derive(Clone)]
struct Slice {
    series: &'static str,
    columns: u16,
    rows: u16,
    position: [f64; 3],
    orientation: [f64; 6],
    pixel_spacing: [f64; 2],
    slope: f64,
    intercept: f64,
    pixels: Vec<i16>,
}

fn ds(v: &[f64]) -> PrimitiveValue {
    PrimitiveValue::Strs(v.iter().map(|x| format!("{x}")).collect())
}

/// Writes `s` as a DICOM file (explicit VR little endian, int16 pixels).
fn write_slice(path: &Path, s: &Slice, instance: usize) {
    let mut obj = InMemDicomObject::new_empty();
    let uid = format!("1.2.3.4.{instance}");
    let mut put = |tag, vr, v: PrimitiveValue| obj.put(DataElement::new(tag, vr, v));
    put(tags::SOP_CLASS_UID, VR::UI, PrimitiveValue::from(CT_IMAGE));
    put(
        tags::SOP_INSTANCE_UID,
        VR::UI,
        PrimitiveValue::from(uid.as_str()),
    );
    put(
        tags::SERIES_INSTANCE_UID,
        VR::UI,
        PrimitiveValue::from(s.series),
    );
    put(
        tags::INSTANCE_NUMBER,
        VR::IS,
        PrimitiveValue::from(format!("{instance}")),
    );
    put(tags::IMAGE_POSITION_PATIENT, VR::DS, ds(&s.position));
    put(tags::IMAGE_ORIENTATION_PATIENT, VR::DS, ds(&s.orientation));
    put(tags::PIXEL_SPACING, VR::DS, ds(&s.pixel_spacing));
    put(tags::RESCALE_SLOPE, VR::DS, ds(&[s.slope]));
    put(tags::RESCALE_INTERCEPT, VR::DS, ds(&[s.intercept]));
    put(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16));
    put(
        tags::PHOTOMETRIC_INTERPRETATION,
        VR::CS,
        PrimitiveValue::from("MONOCHROME2"),
    );
    put(tags::ROWS, VR::US, PrimitiveValue::from(s.rows));
    put(tags::COLUMNS, VR::US, PrimitiveValue::from(s.columns));
    put(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(16u16));
    put(tags::BITS_STORED, VR::US, PrimitiveValue::from(16u16));
    put(tags::HIGH_BIT, VR::US, PrimitiveValue::from(15u16));
    put(
        tags::PIXEL_REPRESENTATION,
        VR::US,
        PrimitiveValue::from(1u16),
    );
    put(
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::I16(s.pixels.iter().copied().collect()),
    );
    let file = obj
        .with_meta(
            FileMetaTableBuilder::new()
                .transfer_syntax(EXPLICIT_LE)
                .media_storage_sop_class_uid(CT_IMAGE)
                .media_storage_sop_instance_uid(uid.as_str()),
        )
        .unwrap();
    file.write_to_file(path).unwrap();
}

/// A 4x3 slice at `position`, axis-aligned, pixel i holding `base + i`.
fn slice_at(position: [f64; 3], base: i16) -> Slice {
    Slice {
        series: "1.2.3.99",
        columns: 4,
        rows: 3,
        position,
        orientation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        pixel_spacing: [0.5, 0.25],
        slope: 1.0,
        intercept: 0.0,
        pixels: (0..12).map(|i| base + i).collect(),
    }
}

/// Writes `slices` into a fresh folder under `root`, file `k` named
/// `names[k]`.
fn series(root: &Path, folder: &str, slices: &[Slice], names: &[&str]) -> PathBuf {
    let dir = root.join(folder);
    std::fs::create_dir_all(&dir).unwrap();
    for (k, (s, n)) in slices.iter().zip(names).enumerate() {
        write_slice(&dir.join(n), s, k + 1);
    }
    dir
}

fn world(v: &flexiso::field::io::Volume, [i, j, k]: [usize; 3]) -> [f64; 3] {
    let [x, y, _] = v.field.dims();
    v.field.world_position((i + x * (j + y * k)) as u32)
}

fn assert_close(a: [f64; 3], b: [f64; 3], what: &str) {
    assert!(
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6),
        "{what}: {a:?} != {b:?}"
    );
}

#[test]
fn simpleitk_series_reads_as_neghip_rescaled_and_placed_in_lps() {
    let (Some(dir), Some(neghip)) = (
        common::dataset("formats/real-tools/neghip_dicom"),
        common::dataset("neghip.nrrd"),
    ) else {
        return;
    };
    let neghip = read(&neghip).unwrap().field;
    let v = read(&dir).unwrap();
    assert_eq!(v.field.dims(), [64, 64, 64]);
    assert!(v.format.starts_with("DICOM (64 slices"), "{}", v.format);
    let expected: Vec<f64> = (0..neghip.len())
        .map(|i| 4.0 * neghip.value(i as u32) - 1000.0)
        .collect();
    assert_eq!(as_f64(v.field.values()), expected, "4 v - 1000");
    assert_eq!(v.field.spacing(), [0.8, 0.8, 2.0]);
    let g = v.field.geometry();
    assert_eq!(g.space, Space::Lps);
    // SimpleITK's TransformIndexToPhysicalPoint: origin + index * spacing
    // (identity direction).
    for idx in [[0, 0, 0], [63, 0, 0], [0, 63, 0], [0, 0, 63], [10, 20, 30]] {
        let want = [
            -25.6 + 0.8 * idx[0] as f64,
            -25.6 + 0.8 * idx[1] as f64,
            100.0 + 2.0 * idx[2] as f64,
        ];
        assert_close(world(&v, idx), want, &format!("voxel {idx:?}"));
    }
}

#[test]
fn slices_are_ordered_by_position_not_by_file_name() {
    let tmp = tempfile::tempdir().unwrap();
    // Positions 10, 12.5, 15, 17.5 along z, written under names that sort
    // the other way round and out of order.
    let slices: Vec<Slice> = (0..4)
        .map(|k| slice_at([-3.0, 7.0, 10.0 + 2.5 * k as f64], 100 * k as i16))
        .collect();
    let dir = series(
        tmp.path(),
        "s",
        &slices,
        &["b9.dcm", "a1.dcm", "z0.dcm", "c5.dcm"],
    );
    let v = read(&dir).unwrap();
    assert_eq!(v.field.dims(), [4, 3, 4]);
    assert_eq!(v.field.spacing(), [0.25, 0.5, 2.5]);
    let want: Vec<f64> = (0..4)
        .flat_map(|k| (0..12).map(move |i| f64::from(100 * k + i)))
        .collect();
    assert_eq!(as_f64(v.field.values()), want);
    assert!(
        matches!(v.field.values(), Values::I16(_)),
        "slope 1, intercept 0 keeps int16"
    );
    assert_close(world(&v, [0, 0, 0]), [-3.0, 7.0, 10.0], "origin");
    assert_close(
        world(&v, [3, 2, 3]),
        [-3.0 + 0.75, 7.0 + 1.0, 17.5],
        "far corner",
    );
}

#[test]
fn a_rotated_orientation_places_rows_columns_and_slices_along_it() {
    let tmp = tempfile::tempdir().unwrap();
    // Rows run along +y, columns along -z (a sagittal series): the normal
    // row x column is (0,1,0) x (0,0,-1) = (-1, 0, 0); slices step by 3
    // along it (descending x). Written in reverse order.
    let row = [0.0, 1.0, 0.0];
    let col = [0.0, 0.0, -1.0];
    let slices: Vec<Slice> = (0..3)
        .rev()
        .map(|k| Slice {
            orientation: [row[0], row[1], row[2], col[0], col[1], col[2]],
            ..slice_at([5.0 - 3.0 * k as f64, 1.0, 2.0], 10 * k as i16)
        })
        .collect();
    let dir = series(tmp.path(), "sag", &slices, &["1.dcm", "2.dcm", "3.dcm"]);
    let v = read(&dir).unwrap();
    assert_eq!(v.field.spacing(), [0.25, 0.5, 3.0]);
    assert_eq!(v.field.value(0), 0.0, "the slice at x = 5 comes first");
    for idx in [[0, 0, 0], [3, 0, 0], [0, 2, 0], [1, 1, 2]] {
        let [i, j, k] = idx.map(|c| c as f64);
        // P0 + i * 0.25 * row + j * 0.5 * col + k * 3 * normal
        let want = [5.0 - 3.0 * k, 1.0 + 0.25 * i, 2.0 - 0.5 * j];
        assert_close(world(&v, idx), want, &format!("voxel {idx:?}"));
    }
}

#[test]
fn rescale_slope_and_intercept_are_applied_per_slice() {
    let tmp = tempfile::tempdir().unwrap();
    // CT's usual rescale: integral, so the values stay integers.
    let ct: Vec<Slice> = (0..3)
        .map(|k| Slice {
            slope: 2.0,
            intercept: -1024.0,
            ..slice_at([0.0, 0.0, k as f64], 0)
        })
        .collect();
    let v = read(&series(tmp.path(), "ct", &ct, &["a.dcm", "b.dcm", "c.dcm"])).unwrap();
    let vals = as_f64(v.field.values());
    assert_eq!(vals[5], 2.0 * 5.0 - 1024.0);
    assert!(
        matches!(v.field.values(), Values::I16(_)),
        "{:?}",
        v.field.values().type_name()
    );
    assert!(v.format.contains("rescaled by 2 + -1024"), "{}", v.format);
    // PET-like: each slice its own non-integral slope.
    let pet: Vec<Slice> = (0..3)
        .map(|k| Slice {
            slope: 0.5 * (k + 1) as f64,
            intercept: 0.25,
            ..slice_at([0.0, 0.0, k as f64], 0)
        })
        .collect();
    let v = read(&series(
        tmp.path(),
        "pet",
        &pet,
        &["a.dcm", "b.dcm", "c.dcm"],
    ))
    .unwrap();
    let vals = as_f64(v.field.values());
    for k in 0..3 {
        for i in 0..12 {
            let want = 0.5 * (k + 1) as f64 * i as f64 + 0.25;
            assert_eq!(vals[12 * k + i], want, "slice {k} pixel {i}");
        }
    }
    assert!(v.format.contains("per slice"), "{}", v.format);
}

#[test]
fn a_folder_of_two_series_is_refused_naming_both() {
    let tmp = tempfile::tempdir().unwrap();
    let mut slices: Vec<Slice> = (0..4).map(|k| slice_at([0.0, 0.0, k as f64], 0)).collect();
    slices[2].series = "1.2.3.77";
    slices[3].series = "1.2.3.77";
    let dir = series(
        tmp.path(),
        "two",
        &slices,
        &["1.dcm", "2.dcm", "3.dcm", "4.dcm"],
    );
    let msg = fails(&dir);
    assert!(msg.contains("2 DICOM series"), "{msg}");
    assert!(
        msg.contains("1.2.3.77 (2 files)") && msg.contains("1.2.3.99 (2 files)"),
        "{msg}"
    );
}

#[test]
fn a_gap_in_the_positions_is_reported_as_missing_slices() {
    let tmp = tempfile::tempdir().unwrap();
    let slices: Vec<Slice> = [0.0, 2.0, 4.0, 10.0, 12.0]
        .iter()
        .map(|&z| slice_at([0.0, 0.0, z], 0))
        .collect();
    let dir = series(
        tmp.path(),
        "gap",
        &slices,
        &["1.dcm", "2.dcm", "3.dcm", "4.dcm", "5.dcm"],
    );
    let msg = fails(&dir);
    assert!(msg.contains("missing slices"), "{msg}");
    assert!(
        msg.contains("3.dcm and 4.dcm") && msg.contains("about 2 missing"),
        "{msg}"
    );
}

#[test]
fn two_slices_at_one_position_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let slices: Vec<Slice> = [0.0, 1.0, 1.0, 2.0]
        .iter()
        .map(|&z| slice_at([0.0, 0.0, z], 0))
        .collect();
    let msg = fails(&series(
        tmp.path(),
        "dup",
        &slices,
        &["1.dcm", "2.dcm", "3.dcm", "4.dcm"],
    ));
    assert!(msg.contains("same position"), "{msg}");
}

#[test]
fn slices_of_different_sizes_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let mut slices: Vec<Slice> = (0..3).map(|k| slice_at([0.0, 0.0, k as f64], 0)).collect();
    slices[1].columns = 3;
    slices[1].rows = 4;
    let msg = fails(&series(
        tmp.path(),
        "size",
        &slices,
        &["1.dcm", "2.dcm", "3.dcm"],
    ));
    assert!(msg.contains("slice size is 3x4"), "{msg}");
}

#[test]
fn a_compressed_transfer_syntax_is_refused_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let slices: Vec<Slice> = (0..2).map(|k| slice_at([0.0, 0.0, k as f64], 0)).collect();
    let dir = series(tmp.path(), "rle", &slices, &["1.dcm", "2.dcm"]);
    // RLE Lossless's UID has explicit VR little endian's length, and its
    // data set is explicit VR little endian: patch the file meta.
    let p = dir.join("2.dcm");
    let bytes = std::fs::read(&p).unwrap();
    let at = bytes
        .windows(EXPLICIT_LE.len())
        .position(|w| w == EXPLICIT_LE.as_bytes())
        .unwrap();
    let mut patched = bytes.clone();
    patched[at..at + EXPLICIT_LE.len()].copy_from_slice(b"1.2.840.10008.1.2.5");
    std::fs::write(&p, patched).unwrap();
    let msg = fails(&dir);
    assert!(
        msg.contains("RLE Lossless") && msg.contains("decompress"),
        "{msg}"
    );
}

#[test]
fn one_dicom_file_reads_as_one_slice() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("one.dcm");
    write_slice(&p, &slice_at([1.0, 2.0, 3.0], 7), 1);
    let v = read(&p).unwrap();
    assert_eq!(v.field.dims(), [4, 3, 1]);
    assert_eq!(v.field.value(0), 7.0);
    assert_close(v.field.world_position(0), [1.0, 2.0, 3.0], "origin");
    // The same file without its extension is found by its magic.
    let bare = tmp.path().join("IM0001");
    std::fs::copy(&p, &bare).unwrap();
    assert_eq!(read(&bare).unwrap().field.values(), v.field.values());
}

#[test]
fn info_names_the_dicom_series_and_its_lps_origin() {
    let Some(dir) = common::dataset("formats/real-tools/neghip_dicom") else {
        return;
    };
    let run = common::flexiso(&["info", dir.to_str().unwrap()]);
    assert!(run.success(), "{}", run.stderr);
    assert!(run.stdout.contains("DICOM (64 slices)"), "{}", run.stdout);
    assert!(run.stdout.contains("LPS"), "{}", run.stdout);
}
