//! Raw, MetaImage, VTK legacy, VTK XML, NIfTI-1 and image-stack readers:
//! each format's variants round-trip the reference values, and the shared
//! data in other formats matches its NRRD twin.
#![allow(clippy::unwrap_used)]

mod common;
use common::formats::*;

use base64::Engine as _;
use flexiso::field::Values;
use flexiso::field::io::{RawLayout, ReadOptions, read_volume};

// ---------------------------------------------------------------- raw

#[test]
fn raw_layout_from_name_for_every_type() {
    let dir = tempfile::tempdir().unwrap();
    for ty in TYPES {
        let vals = reference(ty, 3 * 4 * 5);
        let p = write(
            dir.path(),
            &format!("vol_3x4x5_{ty}.raw"),
            &encode(&vals, ty, false),
        );
        let v = read(&p).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(v.field.dims(), [3, 4, 5]);
        assert_eq!(as_f64(v.field.values()), vals, "{ty}");
    }
    let p = write(
        dir.path(),
        "img_4x2_int16.raw",
        &encode(&reference("int16", 8), "int16", false),
    );
    assert_eq!(read(&p).unwrap().field.dims(), [4, 2, 1]);
}

#[test]
fn raw_layout_from_options_reads_big_endian() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("float64", 8);
    let p = write(dir.path(), "whatever.bin", &encode(&vals, "float64", true));
    let opts = ReadOptions {
        raw: Some(RawLayout {
            dims: [2, 2, 2],
            scalar_type: "double".into(),
            big_endian: true,
        }),
        ..ReadOptions::default()
    };
    let v = read_volume(&p, &opts).unwrap();
    assert_eq!(as_f64(v.field.values()), vals);
}

#[test]
fn shared_raw_neghip_matches_its_nrrd() {
    let (Some(raw), Some(nrrd)) = (
        common::dataset("formats/neghip_64x64x64_uint8.raw"),
        common::dataset("neghip.nrrd"),
    ) else {
        return;
    };
    let (raw, nrrd) = (read(&raw).unwrap(), read(&nrrd).unwrap());
    assert_eq!(raw.field.dims(), [64, 64, 64]);
    assert_eq!(raw.field.values(), nrrd.field.values());
}

// ---------------------------------------------------------- MetaImage

fn mhd_header(ty: &str, msb: bool, compressed: bool, data_file: &str) -> String {
    format!(
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = {}\nCompressedData = {}\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nElementSpacing = 0.5 1 2\nDimSize = 3 4 5\nElementType = {ty}\nElementDataFile = {data_file}\n",
        if msb { "True" } else { "False" },
        if compressed { "True" } else { "False" },
    )
}

#[test]
fn metaimage_attached_detached_compressed_and_big_endian() {
    let dir = tempfile::tempdir().unwrap();
    for (met, ty) in [
        ("MET_UCHAR", "uint8"),
        ("MET_CHAR", "int8"),
        ("MET_USHORT", "uint16"),
        ("MET_SHORT", "int16"),
        ("MET_UINT", "uint32"),
        ("MET_INT", "int32"),
        ("MET_LONG_LONG", "int64"),
        ("MET_ULONG_LONG", "uint64"),
        ("MET_FLOAT", "float32"),
        ("MET_DOUBLE", "float64"),
    ] {
        let vals = reference(ty, 60);
        for msb in [false, true] {
            let bytes = encode(&vals, ty, msb);
            // .mha, attached
            let mut b = mhd_header(met, msb, false, "LOCAL").into_bytes();
            b.extend_from_slice(&bytes);
            let p = write(dir.path(), "a.mha", &b);
            let v = read(&p).unwrap_or_else(|e| panic!("{met}: {e}"));
            assert_eq!(v.field.dims(), [3, 4, 5]);
            assert_eq!(v.field.spacing(), [0.5, 1.0, 2.0]);
            assert_eq!(as_f64(v.field.values()), vals, "{met} mha msb={msb}");
            // .mhd + .zraw
            write(dir.path(), "a.zraw", &zlib(&bytes));
            let p = write(
                dir.path(),
                "a.mhd",
                mhd_header(met, msb, true, "a.zraw").as_bytes(),
            );
            assert_eq!(
                as_f64(read(&p).unwrap().field.values()),
                vals,
                "{met} zraw msb={msb}"
            );
            // .mhd + .raw
            write(dir.path(), "b.raw", &bytes);
            let p = write(
                dir.path(),
                "b.mhd",
                mhd_header(met, msb, false, "b.raw").as_bytes(),
            );
            assert_eq!(
                as_f64(read(&p).unwrap().field.values()),
                vals,
                "{met} raw msb={msb}"
            );
        }
    }
}

// ---------------------------------------------------------- VTK legacy

#[test]
fn vtk_legacy_binary_is_big_endian_and_ascii_reads() {
    let dir = tempfile::tempdir().unwrap();
    for (vt, ty) in [
        ("unsigned_char", "uint8"),
        ("char", "int8"),
        ("unsigned_short", "uint16"),
        ("short", "int16"),
        ("unsigned_int", "uint32"),
        ("int", "int32"),
        ("long", "int64"),
        ("vtktypeuint64", "uint64"),
        ("float", "float32"),
        ("double", "float64"),
    ] {
        let vals = reference(ty, 24);
        let mut data = encode(&vals, ty, true);
        data.extend_from_slice(b"\nSCALARS other float 1\nLOOKUP_TABLE default\n"); // more arrays follow
        let p = write(
            dir.path(),
            "b.vtk",
            &vtk_legacy([2, 3, 4], vt, false, &data),
        );
        let v = read(&p).unwrap_or_else(|e| panic!("{vt}: {e}"));
        assert_eq!(v.field.dims(), [2, 3, 4]);
        assert_eq!(v.field.spacing(), [1.0, 2.0, 3.0]);
        assert_eq!(as_f64(v.field.values()), vals, "{vt} binary");
        let text: Vec<String> = vals.iter().map(|x| x.to_string()).collect();
        let p = write(
            dir.path(),
            "a.vtk",
            &vtk_legacy([2, 3, 4], vt, true, text.join(" ").as_bytes()),
        );
        assert_eq!(as_f64(read(&p).unwrap().field.values()), vals, "{vt} ascii");
    }
}

// ------------------------------------------------------------- VTK XML

fn vti(
    header_type: &str,
    compressor: &str,
    byte_order: &str,
    array: &str,
    appended: &[u8],
) -> Vec<u8> {
    let mut b = format!(
        "<?xml version=\"1.0\"?>\n<!-- a comment <with> brackets -->\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"{byte_order}\" header_type=\"{header_type}\"{compressor}>\n  <ImageData WholeExtent=\"0 2 1 4 0 4\" Origin=\"0 0 0\" Spacing=\"0.5 0.25 1\">\n  <Piece Extent=\"0 2 1 4 0 4\">\n    <PointData Scalars=\"density\">\n      <DataArray type=\"Float32\" Name=\"other\" format=\"ascii\">1</DataArray>\n{array}\n    </PointData>\n    <CellData>\n    </CellData>\n  </Piece>\n  </ImageData>\n"
    )
    .into_bytes();
    if !appended.is_empty() {
        b.extend_from_slice(b"  <AppendedData encoding=\"raw\">\n   _");
        b.extend_from_slice(appended);
        b.extend_from_slice(b"\n  </AppendedData>\n");
    }
    b.extend_from_slice(b"</VTKFile>\n");
    b
}

fn vtk_name(ty: &str) -> &'static str {
    match ty {
        "uint8" => "UInt8",
        "int8" => "Int8",
        "uint16" => "UInt16",
        "int16" => "Int16",
        "uint32" => "UInt32",
        "int32" => "Int32",
        "uint64" => "UInt64",
        "int64" => "Int64",
        "float32" => "Float32",
        _ => "Float64",
    }
}

fn word(x: usize, u64h: bool, big: bool) -> Vec<u8> {
    match (u64h, big) {
        (true, true) => (x as u64).to_be_bytes().to_vec(),
        (true, false) => (x as u64).to_le_bytes().to_vec(),
        (false, true) => (x as u32).to_be_bytes().to_vec(),
        (false, false) => (x as u32).to_le_bytes().to_vec(),
    }
}

/// VTK's compressed layout: block header then zlib blocks of `block` bytes.
fn compressed(data: &[u8], block: usize, u64h: bool, big: bool) -> (Vec<u8>, Vec<u8>) {
    let blocks: Vec<Vec<u8>> = data.chunks(block).map(zlib).collect();
    let last = data.len() % block;
    let mut h = word(blocks.len(), u64h, big);
    h.extend(word(block, u64h, big));
    h.extend(word(last, u64h, big));
    for b in &blocks {
        h.extend(word(b.len(), u64h, big));
    }
    (h, blocks.concat())
}

#[test]
fn vti_ascii_binary_appended_and_zlib() {
    let dir = tempfile::tempdir().unwrap();
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let n = 3 * 4 * 5;
    for ty in TYPES {
        let vals = reference(ty, n);
        let name = vtk_name(ty);
        let arr = |format: &str, body: &str, extra: &str| {
            format!(
                "      <DataArray type=\"{name}\" Name=\"density\" format=\"{format}\"{extra}>\n{body}\n      </DataArray>"
            )
        };
        let check = |file: &str, bytes: Vec<u8>, what: &str| {
            let p = write(dir.path(), file, &bytes);
            let v = read(&p).unwrap_or_else(|e| panic!("{ty} {what}: {e}"));
            assert_eq!(v.field.dims(), [3, 4, 5], "{ty} {what}");
            assert_eq!(v.field.spacing(), [0.5, 0.25, 1.0]);
            assert_eq!(as_f64(v.field.values()), vals, "{ty} {what}");
        };
        let text: Vec<String> = vals.iter().map(|x| x.to_string()).collect();
        check(
            "a.vti",
            vti(
                "UInt32",
                "",
                "LittleEndian",
                &arr("ascii", &text.join(" "), ""),
                b"",
            ),
            "ascii",
        );
        for (u64h, big) in [(false, false), (true, false), (false, true), (true, true)] {
            let ht = if u64h { "UInt64" } else { "UInt32" };
            let bo = if big { "BigEndian" } else { "LittleEndian" };
            let data = encode(&vals, ty, big);
            // binary, header and data as separate base64 runs (VTK) and as one.
            let sep = format!("{}{}", b64(&word(data.len(), u64h, big)), b64(&data));
            check(
                "b.vti",
                vti(ht, "", bo, &arr("binary", &sep, ""), b""),
                "binary separate",
            );
            let mut joined = word(data.len(), u64h, big);
            joined.extend_from_slice(&data);
            check(
                "c.vti",
                vti(ht, "", bo, &arr("binary", &b64(&joined), ""), b""),
                "binary joined",
            );
            // appended raw, after another array at offset 0.
            let mut app = word(4, u64h, big);
            app.extend_from_slice(&[9, 9, 9, 9]);
            let off = app.len();
            app.extend(word(data.len(), u64h, big));
            app.extend_from_slice(&data);
            check(
                "d.vti",
                vti(
                    ht,
                    "",
                    bo,
                    &arr("appended", "", &format!(" offset=\"{off}\"")),
                    &app,
                ),
                "appended",
            );
            // zlib, inline and appended, with several blocks.
            let comp = " compressor=\"vtkZLibDataCompressor\"";
            let (h, blocks) = compressed(&data, 64, u64h, big);
            check(
                "e.vti",
                vti(
                    ht,
                    comp,
                    bo,
                    &arr("binary", &format!("{}{}", b64(&h), b64(&blocks)), ""),
                    b"",
                ),
                "zlib binary",
            );
            let mut app = h.clone();
            app.extend_from_slice(&blocks);
            check(
                "f.vti",
                vti(ht, comp, bo, &arr("appended", "", " offset=\"0\""), &app),
                "zlib appended",
            );
        }
    }
}

// -------------------------------------------------------------- NIfTI

#[test]
fn nifti_types_endianness_gzip_and_scaling() {
    let dir = tempfile::tempdir().unwrap();
    for (code, ty) in [
        (2i16, "uint8"),
        (4, "int16"),
        (8, "int32"),
        (16, "float32"),
        (64, "float64"),
        (256, "int8"),
        (512, "uint16"),
        (768, "uint32"),
        (1024, "int64"),
        (1280, "uint64"),
    ] {
        let vals = reference(ty, 60);
        let bits = 8 * encode(&[0.0], ty, false).len() as i16;
        for big in [false, true] {
            let mut b = nifti_header([3, 4, 5], code, bits, [0.5, -2.0, 1.5], 0.0, 0.0, big);
            b.extend_from_slice(&encode(&vals, ty, big));
            let p = write(dir.path(), "a.nii", &b);
            let v = read(&p).unwrap_or_else(|e| panic!("{ty}: {e}"));
            assert_eq!(v.field.dims(), [3, 4, 5]);
            assert_eq!(v.field.spacing(), [0.5, 2.0, 1.5]);
            assert_eq!(v.field.values().type_name(), stored(ty));
            assert_eq!(as_f64(v.field.values()), vals, "{ty} big={big}");
            let p = write(dir.path(), "a.nii.gz", &gzip(&b));
            assert_eq!(
                as_f64(read(&p).unwrap().field.values()),
                vals,
                "{ty} gz big={big}"
            );
        }
    }
    // slope 2, intercept -1: float values.
    let vals = reference("int16", 60);
    let mut b = nifti_header([3, 4, 5], 4, 16, [1.0; 3], 2.0, -1.0, false);
    b.extend_from_slice(&encode(&vals, "int16", false));
    let v = read(&write(dir.path(), "s.nii", &b)).unwrap();
    assert_eq!(v.field.values().type_name(), "float32");
    let want: Vec<f64> = vals.iter().map(|x| 2.0 * x - 1.0).collect();
    assert_eq!(as_f64(v.field.values()), want);
    // slope (1, 0) keeps the stored type.
    let mut b = nifti_header([3, 4, 5], 4, 16, [1.0; 3], 1.0, 0.0, false);
    b.extend_from_slice(&encode(&vals, "int16", false));
    assert_eq!(
        read(&write(dir.path(), "t.nii", &b))
            .unwrap()
            .field
            .values()
            .type_name(),
        "int16"
    );
}

#[test]
fn nifti_pair_reads_img_beside_hdr() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("uint16", 60);
    let mut h = nifti_header([3, 4, 5], 512, 16, [1.0; 3], 0.0, 0.0, false);
    h[108..112].copy_from_slice(&0f32.to_le_bytes());
    h[344..348].copy_from_slice(b"ni1\0");
    write(dir.path(), "p.img", &encode(&vals, "uint16", false));
    let p = write(dir.path(), "p.hdr", &h[..348]);
    assert_eq!(as_f64(read(&p).unwrap().field.values()), vals);
}

#[test]
fn shared_colin27_nifti_matches_its_nrrd() {
    let (Some(nii), Some(nrrd)) = (
        common::dataset("formats/colin27_ch2.nii.gz"),
        common::dataset("colin27_ch2.nrrd"),
    ) else {
        return;
    };
    let (nii, nrrd) = (read(&nii).unwrap(), read(&nrrd).unwrap());
    assert_eq!(nii.field.dims(), [181, 217, 181]);
    assert_eq!(nii.field.dims(), nrrd.field.dims());
    assert_eq!(nii.field.spacing(), nrrd.field.spacing());
    assert_eq!(nii.field.values(), nrrd.field.values());
}

// -------------------------------------------------------- image stacks

#[test]
fn png_and_tiff_stacks_in_natural_order() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (5u32, 3u32);
    // 12 slices: slice1..slice12, so lexicographic order would be wrong.
    let stack8 = dir.path().join("png8");
    let stack16 = dir.path().join("png16");
    let tiff16 = dir.path().join("tiff16");
    for d in [&stack8, &stack16, &tiff16] {
        std::fs::create_dir(d).unwrap();
    }
    std::fs::write(stack8.join("notes.txt"), "ignored").unwrap();
    for z in 1..=12u32 {
        let img8 =
            image::GrayImage::from_fn(w, h, |x, y| image::Luma([(x + 10 * y + 20 * z) as u8]));
        img8.save(stack8.join(format!("slice{z}.png"))).unwrap();
        let img16 = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(w, h, |x, y| {
            image::Luma([(x + 10 * y) as u16 + 1000 * z as u16])
        });
        img16.save(stack16.join(format!("slice{z}.png"))).unwrap();
        img16.save(tiff16.join(format!("slice{z}.tif"))).unwrap();
    }
    let v = read(&stack8).unwrap();
    assert_eq!(v.field.dims(), [5, 3, 12]);
    assert_eq!(v.format, "image stack (12 slices)");
    assert!(matches!(v.field.values(), Values::U8(_)));
    let f = &v.field;
    assert_eq!(
        f.values().get(2 + 5 * (1 + 3 * 9)),
        (2 + 10 + 20 * 10) as f64
    );
    for d in [&stack16, &tiff16] {
        let v = read(d).unwrap();
        assert!(
            matches!(v.field.values(), Values::U16(_)),
            "{}",
            d.display()
        );
        for z in 0..12 {
            assert_eq!(
                v.field.values().get(4 + 5 * (2 + 3 * z)),
                (4 + 20 + 1000 * (z + 1)) as f64
            );
        }
    }
    // A single image reads as depth 1.
    let one = read(&stack16.join("slice3.png")).unwrap();
    assert_eq!(one.field.dims(), [5, 3, 1]);
}
