//! World geometry and the files real tools write: origin, spacing and
//! direction from every format that has them, checked against the
//! physical coordinates SimpleITK gives for known voxels
//! (`formats/real-tools/`, skipped when the data folder is absent); a
//! multi-page TIFF, VTK's default `.vti` and its uint8 legacy `.vtk` read
//! as the neghip volume they hold; TIFFs that are not one grayscale volume
//! refused.
#![allow(clippy::unwrap_used)]

mod common;
use common::formats::*;

use flexiso::field::{Geometry, ScalarField, Space};
use std::path::Path;

/// The physical coordinates of the voxels listed in
/// `neghip_oriented_points.json`, as (index, LPS point).
fn sitk_points(dir: &Path) -> Vec<([usize; 3], [f64; 3])> {
    let text = std::fs::read_to_string(dir.join("neghip_oriented_points.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["index_to_physical"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| {
            let idx: Vec<usize> = serde_json::from_str(k).unwrap();
            let p: Vec<f64> = v
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            ([idx[0], idx[1], idx[2]], [p[0], p[1], p[2]])
        })
        .collect()
}

fn vertex(field: &ScalarField, [i, j, k]: [usize; 3]) -> u32 {
    let [x, y, _] = field.dims();
    (i + x * (j + y * k)) as u32
}

fn assert_close(a: [f64; 3], b: [f64; 3], what: &str) {
    assert!(
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-4),
        "{what}: {a:?} != {b:?}"
    );
}

fn neghip() -> Option<ScalarField> {
    Some(read(&common::dataset("neghip.nrrd")?).unwrap().field)
}

#[test]
fn sitk_metaimage_places_voxels_where_simpleitk_does() {
    let (Some(dir), Some(neghip)) = (common::dataset("formats/real-tools"), neghip()) else {
        return;
    };
    let v = read(&dir.join("neghip_oriented_sitk.mha")).unwrap();
    assert_eq!(v.field.values(), neghip.values(), "neghip's values");
    assert_eq!(v.field.geometry().space, Space::Lps);
    for (idx, lps) in sitk_points(&dir) {
        let w = v.field.world_position(vertex(&v.field, idx));
        assert_close(w, lps, &format!("voxel {idx:?}"));
    }
}

#[test]
fn sitk_nifti_places_voxels_where_simpleitk_does_in_ras() {
    let (Some(dir), Some(neghip)) = (common::dataset("formats/real-tools"), neghip()) else {
        return;
    };
    let v = read(&dir.join("neghip_oriented_sitk.nii.gz")).unwrap();
    assert_eq!(v.field.values(), neghip.values(), "neghip's values");
    assert_eq!(v.field.geometry().space, Space::Ras);
    for (idx, lps) in sitk_points(&dir) {
        let w = v.field.world_position(vertex(&v.field, idx));
        // NIfTI is RAS: x and y are LPS's negated.
        assert_close(w, [-lps[0], -lps[1], lps[2]], &format!("voxel {idx:?}"));
        // And the same point once named in LPS.
        let g = v.field.geometry().in_space(Space::Lps);
        let c = v.field.coords(vertex(&v.field, idx));
        let s = v.field.spacing();
        assert_close(
            g.to_world(std::array::from_fn(|a| c[a] as f64 * s[a])),
            lps,
            &format!("voxel {idx:?} in LPS"),
        );
    }
}

#[test]
fn files_real_tools_write_read_as_the_volume_they_hold() {
    let (Some(dir), Some(neghip)) = (common::dataset("formats/real-tools"), neghip()) else {
        return;
    };
    for name in [
        "neghip_multipage.tif",
        "neghip_vtk_default.vti",
        "neghip_vtk_legacy_uint8.vtk",
    ] {
        let v = read(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(v.field.dims(), [64, 64, 64], "{name}");
        assert_eq!(v.field.values(), neghip.values(), "{name}: neghip's values");
    }
}

#[test]
fn nrrd_space_origin_and_directions_place_the_grid() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("uint8", 60);
    let p = write(
        dir.path(),
        "oriented.nrrd",
        &nrrd(
            "uint8",
            &[5, 4, 3],
            "raw",
            "",
            "space: left-posterior-superior\nspace directions: (0,2,0) (-3,0,0) (0,0,0.5)\nspace origin: (10, 20, 30)\n",
            &encode(&vals, "uint8", false),
        ),
    );
    let v = read(&p).unwrap();
    let f = &v.field;
    assert_eq!(f.spacing(), [2.0, 3.0, 0.5]);
    let g = f.geometry();
    assert_eq!(g.space, Space::Lps);
    assert_eq!(g.origin, [10.0, 20.0, 30.0]);
    assert_eq!(
        g.direction,
        [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    );
    // Voxel (1, 1, 2): origin + 1·(0,2,0) + 1·(-3,0,0) + 2·(0,0,0.5).
    assert_close(
        f.world_position(vertex(f, [1, 1, 2])),
        [7.0, 22.0, 31.0],
        "voxel (1, 1, 2)",
    );
}

#[test]
fn vtk_legacy_origin_and_vti_origin_direction_and_extent_place_the_grid() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("uint8", 60);
    let legacy = String::from_utf8(vtk_legacy([5, 4, 3], "unsigned_char", true, &[])).unwrap();
    let text: Vec<String> = vals.iter().map(|v| v.to_string()).collect();
    let legacy = legacy.replace("ORIGIN 0 0 0", "ORIGIN 1 2 3") + &text.join(" ");
    let p = write(dir.path(), "o.vtk", legacy.as_bytes());
    let v = read(&p).unwrap();
    assert_eq!(v.field.geometry().origin, [1.0, 2.0, 3.0]);
    assert_eq!(v.field.geometry().space, Space::Unnamed);

    // An extent starting at (1, 0, 2), a direction swapping x and y.
    let vti = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
         <ImageData WholeExtent=\"1 5 0 3 2 4\" Origin=\"10 20 30\" Spacing=\"1 2 3\" Direction=\"0 1 0 1 0 0 0 0 1\">\n\
         <Piece Extent=\"1 5 0 3 2 4\"><PointData Scalars=\"v\">\n\
         <DataArray type=\"UInt8\" Name=\"v\" format=\"ascii\">{}</DataArray>\n\
         </PointData></Piece></ImageData></VTKFile>\n",
        text.join(" ")
    );
    let p = write(dir.path(), "o.vti", vti.as_bytes());
    let v = read(&p).unwrap();
    let f = &v.field;
    assert_eq!(f.dims(), [5, 4, 3]);
    assert_eq!(as_f64(f.values()), vals);
    // Row-major Direction: axis i along y, axis j along x.
    assert_eq!(
        f.geometry().direction,
        [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    );
    // Vertex 0 is extent point (1, 0, 2): origin + 1·1·(0,1,0) + 2·3·(0,0,1).
    assert_close(f.world_position(0), [10.0, 21.0, 36.0], "vertex 0");
}

#[test]
fn vti_appended_base64_reads_like_raw() {
    use base64::Engine as _;
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("int16", 60);
    let data = encode(&vals, "int16", false);
    let b64 = base64::engine::general_purpose::STANDARD;
    // VTK's layout: the size header and the data as two base64 runs.
    let body = b64.encode((data.len() as u32).to_le_bytes()) + &b64.encode(&data);
    let vti = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\" header_type=\"UInt32\">\n\
         <ImageData WholeExtent=\"0 4 0 3 0 2\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n\
         <Piece Extent=\"0 4 0 3 0 2\"><PointData Scalars=\"v\">\n\
         <DataArray type=\"Int16\" Name=\"v\" format=\"appended\" offset=\"0\"/>\n\
         </PointData></Piece></ImageData>\n<AppendedData encoding=\"base64\">\n   _{body}\n</AppendedData>\n</VTKFile>\n"
    );
    let p = write(dir.path(), "b64.vti", vti.as_bytes());
    let v = read(&p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(as_f64(v.field.values()), vals);
}

#[test]
fn a_tiff_that_is_not_one_grayscale_volume_is_an_error_not_a_misread() {
    let dir = tempfile::tempdir().unwrap();
    let rgb = dir.path().join("rgb.tif");
    image::RgbImage::from_pixel(4, 3, image::Rgb([1, 2, 3]))
        .save(&rgb)
        .unwrap();
    let msg = fails(&rgb);
    assert!(msg.contains("RGB") && msg.contains("grayscale"), "{msg}");
    // A gray one reads, as one page.
    let gray = dir.path().join("gray.tif");
    image::GrayImage::from_fn(4, 3, |x, y| image::Luma([(x + 4 * y) as u8]))
        .save(&gray)
        .unwrap();
    let v = read(&gray).unwrap();
    assert_eq!(v.field.dims(), [4, 3, 1]);
    assert_eq!(
        as_f64(v.field.values()),
        (0..12).map(f64::from).collect::<Vec<_>>()
    );
}

#[test]
fn an_unusable_direction_is_a_warning_and_the_identity() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("uint8", 8);
    let p = write(
        dir.path(),
        "flat.nrrd",
        &nrrd(
            "uint8",
            &[2, 2, 2],
            "raw",
            "",
            "space: RAS\nspace directions: (1,0,0) (2,0,0) (0,0,1)\n",
            &encode(&vals, "uint8", false),
        ),
    );
    let v = read(&p).unwrap();
    assert_eq!(v.field.geometry().direction, Geometry::IDENTITY.direction);
    assert!(
        v.warnings.iter().any(|w| w.contains("degenerate")),
        "{:?}",
        v.warnings
    );
}

/// A NIfTI-2 single file: 540-byte header, 4 bytes of extension flag, then
/// int16 data, with an sform.
fn nifti2(dims: [usize; 3], srow: [[f64; 4]; 3], data: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 544];
    h[0..4].copy_from_slice(&540i32.to_le_bytes());
    h[4..12].copy_from_slice(b"n+2\0\r\n\x1a\n");
    h[12..14].copy_from_slice(&4i16.to_le_bytes()); // int16
    h[14..16].copy_from_slice(&16i16.to_le_bytes());
    let dim = [
        3i64,
        dims[0] as i64,
        dims[1] as i64,
        dims[2] as i64,
        1,
        1,
        1,
        1,
    ];
    for (i, d) in dim.iter().enumerate() {
        h[16 + 8 * i..24 + 8 * i].copy_from_slice(&d.to_le_bytes());
    }
    let pixdim = [1.0f64, 2.0, 3.0, 4.0, 0.0, 0.0, 0.0, 0.0];
    for (i, p) in pixdim.iter().enumerate() {
        h[104 + 8 * i..112 + 8 * i].copy_from_slice(&p.to_le_bytes());
    }
    h[168..176].copy_from_slice(&544i64.to_le_bytes());
    h[348..352].copy_from_slice(&1i32.to_le_bytes()); // sform_code
    for (r, row) in srow.iter().enumerate() {
        for (k, x) in row.iter().enumerate() {
            let o = 400 + 32 * r + 8 * k;
            h[o..o + 8].copy_from_slice(&x.to_le_bytes());
        }
    }
    h.extend_from_slice(data);
    h
}

#[test]
fn nifti2_reads_its_values_spacing_and_sform() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("int16", 60);
    // Axis i along -x (a reflection, as RAS files from LPS scanners are).
    let srow = [
        [-2.0, 0.0, 0.0, 5.0],
        [0.0, 3.0, 0.0, -6.0],
        [0.0, 0.0, 4.0, 7.0],
    ];
    let p = write(
        dir.path(),
        "v2.nii",
        &nifti2([5, 4, 3], srow, &encode(&vals, "int16", false)),
    );
    let v = read(&p).unwrap_or_else(|e| panic!("{e}"));
    assert!(v.format.starts_with("NIfTI-2"), "{}", v.format);
    assert_eq!(v.field.dims(), [5, 4, 3]);
    assert_eq!(as_f64(v.field.values()), vals);
    assert_eq!(v.field.spacing(), [2.0, 3.0, 4.0]);
    let g = v.field.geometry();
    assert_eq!(g.space, Space::Ras);
    assert!(g.is_reflection());
    // Voxel (1, 2, 1) at M · (1, 2, 1, 1).
    assert_close(
        v.field.world_position(vertex(&v.field, [1, 2, 1])),
        [3.0, 0.0, 11.0],
        "voxel (1, 2, 1)",
    );
}

#[test]
fn mgh_and_mgz_read_values_spacing_and_the_ras_placement() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("int16", 60);
    let mut h = vec![0u8; 284];
    let put_i32 = |h: &mut Vec<u8>, o: usize, v: i32| h[o..o + 4].copy_from_slice(&v.to_be_bytes());
    let put_f32 = |h: &mut Vec<u8>, o: usize, v: f32| h[o..o + 4].copy_from_slice(&v.to_be_bytes());
    put_i32(&mut h, 0, 1);
    for (k, d) in [5, 4, 3, 1].iter().enumerate() {
        put_i32(&mut h, 4 + 4 * k, *d);
    }
    put_i32(&mut h, 20, 4); // short
    h[28..30].copy_from_slice(&1i16.to_be_bytes());
    for (k, s) in [2.0f32, 1.0, 3.0].iter().enumerate() {
        put_f32(&mut h, 30 + 4 * k, *s);
    }
    // Mdc: FreeSurfer's conformed orientation: x -> -R, y -> -S, z -> +A.
    let mdc = [-1.0f32, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0];
    for (k, m) in mdc.iter().enumerate() {
        put_f32(&mut h, 42 + 4 * k, *m);
    }
    for (k, c) in [10.0f32, 20.0, 30.0].iter().enumerate() {
        put_f32(&mut h, 78 + 4 * k, *c);
    }
    h.extend_from_slice(&encode(&vals, "int16", true));
    let mgh = write(dir.path(), "v.mgh", &h);
    let mgz = write(dir.path(), "v.mgz", &gzip(&h));
    for p in [mgh, mgz] {
        let v = read(&p).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(v.field.dims(), [5, 4, 3]);
        assert_eq!(as_f64(v.field.values()), vals);
        assert_eq!(v.field.spacing(), [2.0, 1.0, 3.0]);
        assert_eq!(v.field.geometry().space, Space::Ras);
        // Vertex 0 at c_ras - (x: -1·2·5/2, y: -S·1·4/2, z: +A·3·3/2).
        assert_close(v.field.world_position(0), [15.0, 15.5, 32.0], "vertex 0");
    }
}

#[test]
fn vti_lz4_and_lzma_blocks_read_like_zlib() {
    use base64::Engine as _;
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("int16", 60);
    let data = encode(&vals, "int16", false);
    let b64 = base64::engine::general_purpose::STANDARD;
    for (compressor, block) in [
        ("vtkLZ4DataCompressor", {
            let mut out = vec![0u8; lz4_flex::block::get_maximum_output_size(data.len())];
            let n = lz4_flex::block::compress_into(&data, &mut out).unwrap();
            out.truncate(n);
            out
        }),
        ("vtkLZMADataCompressor", {
            let mut out = Vec::new();
            lzma_rs::xz_compress(&mut &data[..], &mut out).unwrap();
            out
        }),
    ] {
        // One block holding everything: nblocks, blocksize, lastblocksize, csize.
        let header: Vec<u8> = [
            1u32,
            data.len() as u32,
            data.len() as u32,
            block.len() as u32,
        ]
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .collect();
        let body = b64.encode(&header) + &b64.encode(&block);
        let vti = format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\" header_type=\"UInt32\" compressor=\"{compressor}\">\n\
             <ImageData WholeExtent=\"0 4 0 3 0 2\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n\
             <Piece Extent=\"0 4 0 3 0 2\"><PointData Scalars=\"v\">\n\
             <DataArray type=\"Int16\" Name=\"v\" format=\"binary\">{body}</DataArray>\n\
             </PointData></Piece></ImageData></VTKFile>\n"
        );
        let p = write(dir.path(), &format!("{compressor}.vti"), vti.as_bytes());
        let v = read(&p).unwrap_or_else(|e| panic!("{compressor}: {e}"));
        assert_eq!(as_f64(v.field.values()), vals, "{compressor}");
    }
}
