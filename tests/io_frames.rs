//! 4D and vector files: one frame (`--frame T`) or one component
//! (`--component C`) is read, the right one; without a choice a file with
//! several is refused with a message naming the option and the range; a
//! choice out of range, or on a file with one, is refused too. Files the
//! tests write: 4D NIfTI (.nii and .nii.gz, frames and dim-5 components),
//! vector MetaImage, 4D MetaImage (.mha and .mhd, with channels too), 4D NRRD (vector first, time last), VTI and legacy VTK
//! with several components, multi-frame MGH.
#![allow(clippy::unwrap_used)]

mod common;
use common::formats::*;

use flexiso::field::io::{ReadOptions, read_volume};
use std::path::Path;

const DIMS: [usize; 3] = [3, 4, 2];
const N: usize = 24;

/// Value of voxel `i` in volume `k` (frame or component).
fn value(k: usize, i: usize) -> f64 {
    (100 * k + i) as f64
}

/// `count` volumes one after the other (frames).
fn frames(count: usize) -> Vec<f64> {
    (0..count)
        .flat_map(|k| (0..N).map(move |i| value(k, i)))
        .collect()
}

/// `count` volumes interleaved (components, the fastest axis).
fn interleaved(count: usize) -> Vec<f64> {
    (0..N)
        .flat_map(|i| (0..count).map(move |k| value(k, i)))
        .collect()
}

fn volume_k(k: usize) -> Vec<f64> {
    (0..N).map(|i| value(k, i)).collect()
}

fn with(frame: Option<usize>, component: Option<usize>) -> ReadOptions {
    ReadOptions {
        frame,
        component,
        ..ReadOptions::default()
    }
}

fn read_with(p: &Path, frame: Option<usize>, component: Option<usize>) -> Vec<f64> {
    let v = read_volume(p, &with(frame, component)).unwrap();
    assert_eq!(v.field.dims(), DIMS, "{}", p.display());
    as_f64(v.field.values())
}

fn fails_with(p: &Path, frame: Option<usize>, component: Option<usize>) -> String {
    let e = read_volume(p, &with(frame, component))
        .unwrap_err()
        .to_string();
    assert!(!e.contains('\n'), "{e}");
    assert!(
        e.contains(&*p.file_name().unwrap().to_string_lossy()),
        "names the file: {e}"
    );
    e
}

/// A NIfTI-1 `.nii` with `dim[4] = t`, `dim[5] = c`, float32 data.
fn nifti_4d(t: usize, c: usize, data: &[f64]) -> Vec<u8> {
    let mut h = nifti_header(DIMS, 16, 32, [1.0; 3], 1.0, 0.0, false);
    let ndim: i16 = if c > 1 { 5 } else { 4 };
    h[40..42].copy_from_slice(&ndim.to_le_bytes());
    h[48..50].copy_from_slice(&(t as i16).to_le_bytes());
    h[50..52].copy_from_slice(&(c as i16).to_le_bytes());
    h.extend_from_slice(&encode(data, "float32", false));
    h
}

#[test]
fn a_4d_nifti_reads_the_chosen_frame_and_refuses_no_choice() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = nifti_4d(3, 1, &frames(3));
    for name in ["f.nii", "f.nii.gz"] {
        let data = if name.ends_with(".gz") {
            gzip(&bytes)
        } else {
            bytes.clone()
        };
        let p = write(dir.path(), name, &data);
        for k in 0..3 {
            assert_eq!(
                read_with(&p, Some(k), None),
                volume_k(k),
                "{name} frame {k}"
            );
        }
        let e = fails_with(&p, None, None);
        assert!(
            e.contains("3 frames") && e.contains("--frame T (0 to 2)"),
            "{e}"
        );
        let e = fails_with(&p, Some(3), None);
        assert!(e.contains("frame 3 does not exist"), "{e}");
        let e = fails_with(&p, Some(0), Some(1));
        assert!(e.contains("component 1 does not exist"), "{e}");
    }
}

#[test]
fn nifti_dim5_components_are_blocks_after_the_frames() {
    let dir = tempfile::tempdir().unwrap();
    // 2 frames x 3 components: block = component * 2 + frame.
    let p = write(dir.path(), "v.nii", &nifti_4d(2, 3, &frames(6)));
    assert_eq!(read_with(&p, Some(1), Some(2)), volume_k(2 * 2 + 1));
    assert_eq!(read_with(&p, Some(0), Some(1)), volume_k(2));
    let e = fails_with(&p, Some(0), None);
    assert!(
        e.contains("3 components") && e.contains("--component C"),
        "{e}"
    );
}

#[test]
fn a_vector_metaimage_reads_the_chosen_channel() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = format!(
        "ObjectType = Image\nNDims = 3\nDimSize = {} {} {}\nElementNumberOfChannels = 3\n\
         ElementType = MET_SHORT\nElementDataFile = LOCAL\n",
        DIMS[0], DIMS[1], DIMS[2]
    )
    .into_bytes();
    b.extend_from_slice(&encode(&interleaved(3), "int16", false));
    let p = write(dir.path(), "vec.mha", &b);
    for k in 0..3 {
        assert_eq!(read_with(&p, None, Some(k)), volume_k(k), "component {k}");
    }
    let e = fails_with(&p, None, None);
    assert!(
        e.contains("3 components") && e.contains("--component C (0 to 2)"),
        "{e}"
    );
    let e = fails_with(&p, Some(1), Some(0));
    assert!(e.contains("frame 1 does not exist"), "{e}");
}

#[test]
fn a_4d_metaimage_reads_the_chosen_frame_with_the_spatial_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let [x, y, z] = DIMS;
    // As ITK writes a 4D image: four numbers for sizes, spacing and
    // offset, a 4×4 matrix; frames one after the other.
    let header = |data: &str| {
        format!(
            "ObjectType = Image\nNDims = 4\nDimSize = {x} {y} {z} 3\n\
             ElementSpacing = 0.5 2 3 1\nOffset = 10 -20 30 0\n\
             TransformMatrix = 0 -1 0 0 1 0 0 0 0 0 1 0 0 0 0 1\n\
             ElementType = MET_FLOAT\nElementDataFile = {data}\n"
        )
    };
    let mut b = header("LOCAL").into_bytes();
    b.extend_from_slice(&encode(&frames(3), "float32", false));
    let mha = write(dir.path(), "t.mha", &b);
    write(dir.path(), "t.raw", &encode(&frames(3), "float32", false));
    let mhd = write(dir.path(), "t.mhd", header("t.raw").as_bytes());
    for p in [&mha, &mhd] {
        for k in 0..3 {
            assert_eq!(read_with(p, Some(k), None), volume_k(k), "frame {k}");
        }
        let v = read_volume(p, &with(Some(2), None)).unwrap();
        assert_eq!(v.field.spacing(), [0.5, 2.0, 3.0], "time is not space");
        let g = v.field.geometry();
        assert_eq!(g.origin, [10.0, -20.0, 30.0]);
        assert_eq!(
            g.direction,
            [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        );
        assert!(v.format.contains("frame 2 of 3"), "{}", v.format);
        let e = fails_with(p, None, None);
        assert!(
            e.contains("3 frames") && e.contains("--frame T (0 to 2)"),
            "{e}"
        );
        assert!(fails_with(p, Some(3), None).contains("frame 3 does not exist"));
    }
    // Frames of vectors: channels fastest, frames slowest.
    let mut b = format!(
        "NDims = 4\nDimSize = {x} {y} {z} 2\nElementNumberOfChannels = 2\n\
         ElementType = MET_SHORT\nElementDataFile = LOCAL\n"
    )
    .into_bytes();
    // Frame f, channel c holds volume 2 f + c.
    let data: Vec<f64> = (0..2)
        .flat_map(|f| (0..N).flat_map(move |i| (0..2).map(move |c| value(2 * f + c, i))))
        .collect();
    b.extend_from_slice(&encode(&data, "int16", false));
    let p = write(dir.path(), "tv.mha", &b);
    assert_eq!(read_with(&p, Some(1), Some(0)), volume_k(2));
    assert_eq!(read_with(&p, Some(0), Some(1)), volume_k(1));
    assert!(fails_with(&p, Some(1), None).contains("--component C (0 to 1)"));
    // A file shorter than its frames is refused, not misread.
    let mut b = header("LOCAL").into_bytes();
    b.extend_from_slice(&encode(&frames(2), "float32", false));
    let short = write(dir.path(), "short.mha", &b);
    assert!(fails_with(&short, Some(0), None).contains("truncated"));
}

#[test]
fn a_4d_nrrd_reads_a_vector_component_or_a_time_frame() {
    let dir = tempfile::tempdir().unwrap();
    let [x, y, z] = DIMS;
    let vector = nrrd(
        "uint16",
        &[2, x, y, z],
        "raw",
        "little",
        "kinds: vector domain domain domain\n",
        &encode(&interleaved(2), "uint16", false),
    );
    let p = write(dir.path(), "vec.nrrd", &vector);
    assert_eq!(read_with(&p, None, Some(1)), volume_k(1));
    assert!(fails_with(&p, None, None).contains("--component C (0 to 1)"));
    let time = nrrd(
        "float32",
        &[x, y, z, 4],
        "gzip",
        "little",
        "space directions: (1,0,0) (0,2,0) (0,0,3) none\n",
        &gzip(&encode(&frames(4), "float32", false)),
    );
    let p = write(dir.path(), "time.nrrd", &time);
    let v = read_volume(&p, &with(Some(3), None)).unwrap();
    assert_eq!(as_f64(v.field.values()), volume_k(3));
    assert_eq!(
        v.field.spacing(),
        [1.0, 2.0, 3.0],
        "the time axis is not space"
    );
    assert!(v.format.contains("frame 3 of 4"), "{}", v.format);
    // Without kinds or directions there is no telling which axis is time.
    let bare = nrrd(
        "uint8",
        &[x, y, z, 2],
        "raw",
        "",
        "",
        &encode(&frames(2), "uint8", false),
    );
    let e = fails_with(&write(dir.path(), "bare.nrrd", &bare), Some(0), None);
    assert!(e.contains("dimension 4"), "{e}");
}

#[test]
fn vti_and_legacy_vtk_with_several_components_read_the_chosen_one() {
    let dir = tempfile::tempdir().unwrap();
    let [x, y, z] = DIMS;
    let text: Vec<String> = interleaved(2).iter().map(|v| format!("{v}")).collect();
    let vti = format!(
        r#"<?xml version="1.0"?>
<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian">
  <ImageData WholeExtent="0 {} 0 {} 0 {}" Origin="0 0 0" Spacing="1 1 1">
    <Piece Extent="0 {} 0 {} 0 {}">
      <PointData Scalars="v">
        <DataArray type="Float32" Name="v" NumberOfComponents="2" format="ascii">{}</DataArray>
      </PointData>
    </Piece>
  </ImageData>
</VTKFile>
"#,
        x - 1,
        y - 1,
        z - 1,
        x - 1,
        y - 1,
        z - 1,
        text.join(" ")
    );
    let p = write(dir.path(), "two.vti", vti.as_bytes());
    assert_eq!(read_with(&p, None, Some(1)), volume_k(1));
    assert!(fails_with(&p, None, None).contains("2 components"));

    let three: Vec<String> = interleaved(3).iter().map(|v| format!("{v}")).collect();
    let vtk = format!(
        "# vtk DataFile Version 3.0\nvec\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS {x} {y} {z}\n\
         SPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA {N}\nSCALARS v float 3\nLOOKUP_TABLE default\n{}\n",
        three.join(" ")
    );
    let p = write(dir.path(), "three.vtk", vtk.as_bytes());
    assert_eq!(read_with(&p, None, Some(2)), volume_k(2));
    assert!(fails_with(&p, None, None).contains("--component C (0 to 2)"));
}

#[test]
fn a_multi_frame_mgh_reads_the_chosen_frame() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = vec![0u8; 284];
    let put = |h: &mut Vec<u8>, at: usize, v: i32| h[at..at + 4].copy_from_slice(&v.to_be_bytes());
    put(&mut h, 0, 1);
    put(&mut h, 4, DIMS[0] as i32);
    put(&mut h, 8, DIMS[1] as i32);
    put(&mut h, 12, DIMS[2] as i32);
    put(&mut h, 16, 2);
    put(&mut h, 20, 3); // float32
    h.extend_from_slice(&encode(&frames(2), "float32", true));
    let p = write(dir.path(), "two.mgz", &gzip(&h));
    assert_eq!(read_with(&p, Some(1), None), volume_k(1));
    assert!(fails_with(&p, None, None).contains("--frame T (0 to 1)"));
}

#[test]
fn a_choice_on_a_3d_scalar_file_is_refused_not_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "s.nrrd",
        &nrrd(
            "uint8",
            &DIMS,
            "raw",
            "",
            "",
            &encode(&volume_k(0), "uint8", false),
        ),
    );
    assert_eq!(
        read_with(&p, Some(0), Some(0)),
        volume_k(0),
        "0 is the only one"
    );
    let e = fails_with(&p, Some(2), None);
    assert!(
        e.contains("frame 2 does not exist: the file has 1 frame"),
        "{e}"
    );
    let e = fails_with(&p, None, Some(1));
    assert!(e.contains("component 1 does not exist"), "{e}");
}

#[test]
fn the_command_line_takes_frame_and_component() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "f.nii", &nifti_4d(3, 1, &frames(3)));
    let path = p.to_str().unwrap();
    let run = common::flexiso(&["info", path]);
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("--frame T (0 to 2)"), "{}", run.stderr);
    let run = common::flexiso(&["info", path, "--frame", "2", "--json"]);
    assert!(run.success(), "{}", run.stderr);
    let json: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    assert!(
        json["format"].as_str().unwrap().contains("frame 2 of 3"),
        "{json}"
    );
}

/// A legacy VTK STRUCTURED_POINTS header of `DIMS` whose point data is
/// announced by `attribute` (the lines up to where the data starts).
fn vtk_header(mode: &str, attribute: &str) -> String {
    let [x, y, z] = DIMS;
    format!(
        "# vtk DataFile Version 3.0\nattributes\n{mode}\nDATASET STRUCTURED_POINTS\n\
         DIMENSIONS {x} {y} {z}\nSPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA {N}\n{attribute}\n"
    )
}

#[test]
fn legacy_vtk_reads_every_point_attribute_kind_by_component() {
    let dir = tempfile::tempdir().unwrap();
    // (attribute line, components): binary big-endian float32 and int16,
    // and ASCII.
    let kinds = [
        ("VECTORS velocity float", 3),
        ("NORMALS n float", 3),
        ("TENSORS stress float", 9),
        ("TEXTURE_COORDINATES uv 2 float", 2),
        ("FIELD FieldData 2\ndensity 2 24 float", 2),
    ];
    for (i, (attribute, k)) in kinds.iter().enumerate() {
        let data = interleaved(*k);
        let mut bin = vtk_header("BINARY", attribute).into_bytes();
        for v in &data {
            bin.extend_from_slice(&(*v as f32).to_be_bytes());
        }
        let p = write(dir.path(), &format!("bin{i}.vtk"), &bin);
        for c in [0, k - 1] {
            assert_eq!(read_with(&p, None, Some(c)), volume_k(c), "{attribute}");
        }
        let e = fails_with(&p, None, None);
        assert!(
            e.contains(&format!("--component C (0 to {})", k - 1)),
            "{e}"
        );

        let short = attribute.replace("float", "short");
        let mut bin = vtk_header("BINARY", &short).into_bytes();
        for v in &data {
            bin.extend_from_slice(&(*v as i16).to_be_bytes());
        }
        let p = write(dir.path(), &format!("short{i}.vtk"), &bin);
        assert_eq!(read_with(&p, None, Some(1)), volume_k(1), "{short}");

        let text: Vec<String> = data.iter().map(|v| format!("{v}")).collect();
        let ascii = vtk_header("ASCII", attribute) + &text.join(" ") + "\n";
        let p = write(dir.path(), &format!("ascii{i}.vtk"), ascii.as_bytes());
        assert_eq!(
            read_with(&p, None, Some(k - 1)),
            volume_k(k - 1),
            "{attribute}"
        );
    }
    // A FIELD array of other than POINT_DATA tuples, a type VTK does not
    // name, and arrays of cells or of the dataset are refused, named.
    let cases = [
        (vtk_header("ASCII", "FIELD f 1\nd 1 7 float"), "7 tuples"),
        (vtk_header("ASCII", "VECTORS v complex"), "complex"),
    ];
    for (i, (text, says)) in cases.iter().enumerate() {
        let p = write(dir.path(), &format!("bad{i}.vtk"), text.as_bytes());
        let e = fails_with(&p, None, Some(0));
        assert!(e.contains(says), "{e}");
    }
    let [x, y, z] = DIMS;
    let cells = format!(
        "# vtk DataFile Version 3.0\nc\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS {x} {y} {z}\n\
         SPACING 1 1 1\nORIGIN 0 0 0\nCELL_DATA 6\nVECTORS v float\n"
    );
    let p = write(dir.path(), "cells.vtk", cells.as_bytes());
    assert!(fails_with(&p, None, Some(0)).contains("before POINT_DATA"));
}
