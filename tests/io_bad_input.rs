//! Bad input, one test per kind: every failure is a one-line error naming
//! the file and the problem, never a panic, and never an allocation the
//! file cannot back.
#![allow(clippy::unwrap_used)]

mod common;
use common::formats::*;

use flexiso::field::io::{NanPolicy, RawLayout, ReadError, ReadOptions, read_volume};
use flexiso::field::{FieldError, Values};

fn nrrd_u8(sizes: &[usize], encoding: &str, data: &[u8]) -> Vec<u8> {
    nrrd("uint8", sizes, encoding, "", "", data)
}

fn unlimited() -> ReadOptions {
    ReadOptions {
        max_memory: Some(u64::MAX),
        ..ReadOptions::default()
    }
}

#[test]
fn truncated_data_is_refused_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = fails(&write(d, "t.nrrd", &nrrd_u8(&[4, 4, 4], "raw", &[0; 63])));
    assert!(
        m.contains("truncated") && m.contains("64") && m.contains("63"),
        "{m}"
    );
    let gz = gzip(&[0; 63]);
    let m = fails(&write(d, "t2.nrrd", &nrrd_u8(&[4, 4, 4], "gzip", &gz)));
    assert!(m.contains("truncated") && m.contains("after 63"), "{m}");
    // A gzip stream cut short.
    let gz = gzip(&(0..64u8).collect::<Vec<_>>());
    let m = fails(&write(
        d,
        "t3.nrrd",
        &nrrd_u8(&[4, 4, 4], "gzip", &gz[..gz.len() / 2]),
    ));
    assert!(m.contains("gzip"), "{m}");
    let m = fails(&write(d, "t_4x4x4_uint16.raw", &[0; 127]));
    assert!(
        m.contains("truncated") && m.contains("128") && m.contains("127"),
        "{m}"
    );
    let mut b = nifti_header([4, 4, 4], 2, 8, [1.0; 3], 0.0, 0.0, false);
    b.extend_from_slice(&[0; 10]);
    let m = fails(&write(d, "t.nii", &b));
    assert!(m.contains("truncated"), "{m}");
    let m = fails(&write(
        d,
        "t.vtk",
        &vtk_legacy([4, 4, 4], "short", false, &[0; 100]),
    ));
    assert!(m.contains("truncated"), "{m}");
    let m = fails(&write(
        d,
        "ta.vtk",
        &vtk_legacy([4, 4, 4], "short", true, b"1 2 3"),
    ));
    assert!(m.contains("truncated"), "{m}");
    let mut b =
        b"NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n".to_vec();
    b.extend_from_slice(&[1; 5]);
    let m = fails(&write(d, "t.mha", &b));
    assert!(m.contains("truncated"), "{m}");
    let m = fails(&write(d, "short.nii", b"\x5c\x01\x00\x00abc"));
    assert!(m.contains("348"), "{m}");
}

#[test]
fn extra_data_is_an_error_for_raw_nrrd_and_metaimage_and_a_warning_for_nifti() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = fails(&write(d, "e_2x2x2_uint8.raw", &[0; 9]));
    assert!(m.contains("1 bytes longer"), "{m}");
    let m = fails(&write(d, "e.nrrd", &nrrd_u8(&[2, 2, 2], "raw", &[0; 10])));
    assert!(m.contains("2 bytes longer"), "{m}");
    let m = fails(&write(
        d,
        "e2.nrrd",
        &nrrd_u8(&[2, 2, 2], "gzip", &gzip(&[0; 9])),
    ));
    assert!(m.contains("more than"), "{m}");
    let m = fails(&write(
        d,
        "e3.nrrd",
        &nrrd_u8(&[2, 2, 2], "ascii", b"1 2 3 4 5 6 7 8 9"),
    ));
    assert!(m.contains("longer"), "{m}");
    let mut b = nifti_header([2, 2, 2], 2, 8, [1.0; 3], 0.0, 0.0, false);
    b.extend_from_slice(&[0; 12]);
    let v = read(&write(d, "pad.nii", &b)).unwrap();
    assert_eq!(v.warnings.len(), 1, "{:?}", v.warnings);
}

#[test]
fn header_and_data_size_mismatch_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // dimension 3 while `sizes` lists two numbers.
    let b = String::from_utf8(nrrd_u8(&[2, 2], "raw", &[0; 4])).unwrap();
    let m = fails(&write(
        d,
        "m.nrrd",
        b.replace("dimension: 2", "dimension: 3").as_bytes(),
    ));
    assert!(m.contains("dimension"), "{m}");
    let mut b = vtk_legacy([2, 2, 2], "unsigned_char", false, &[0; 8]);
    let s = String::from_utf8_lossy(&b).replace("POINT_DATA 8", "POINT_DATA 9");
    b = s.into_bytes();
    let m = fails(&write(d, "m.vtk", &b));
    assert!(m.contains("POINT_DATA 9"), "{m}");
    let vti = "<VTKFile type=\"ImageData\" byte_order=\"LittleEndian\"><ImageData WholeExtent=\"0 1 0 1 0 1\"><Piece><PointData><DataArray type=\"UInt8\" format=\"binary\">BwAAAAABAgMEBQY=</DataArray></PointData></Piece></ImageData></VTKFile>";
    let m = fails(&write(d, "m.vti", vti.as_bytes()));
    assert!(m.contains("7 bytes") && m.contains("8"), "{m}");
    let m = fails(&write(
        d,
        "m.mha",
        b"NDims = 3\nDimSize = 2 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
    ));
    assert!(m.contains("DimSize"), "{m}");
}

#[test]
fn zero_dimensions_are_refused_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for p in [
        write(d, "z.nrrd", &nrrd_u8(&[4, 0, 4], "raw", &[])),
        write(d, "z_4x0x4_uint8.raw", &[]),
        write(
            d,
            "z.mha",
            b"NDims = 3\nDimSize = 4 0 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
        ),
        write(
            d,
            "z.vtk",
            &vtk_legacy([4, 0, 4], "unsigned_char", false, &[]),
        ),
    ] {
        let m = fails(&p);
        assert!(m.contains("zero"), "{m}");
    }
    let m = fails(&write(
        d,
        "z.nii",
        &nifti_header([4, 0, 4], 2, 8, [1.0; 3], 0.0, 0.0, false),
    ));
    assert!(m.contains("dim[2] = 0"), "{m}");
    let vti = "<VTKFile type=\"ImageData\"><ImageData WholeExtent=\"0 3 5 2 0 3\"><Piece><PointData><DataArray type=\"UInt8\" format=\"ascii\">1</DataArray></PointData></Piece></ImageData></VTKFile>";
    let m = fails(&write(d, "z.vti", vti.as_bytes()));
    assert!(m.contains("extent"), "{m}");
}

#[test]
fn dims_that_overflow_or_exceed_the_engine_limit_are_refused_before_allocation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let p = write(d, "o.nrrd", &nrrd_u8(&[usize::MAX, 2, 2], "raw", &[0; 8]));
    let e = read_volume(&p, &unlimited()).unwrap_err();
    assert!(
        matches!(
            e,
            ReadError::Field {
                error: FieldError::TooLarge(_),
                ..
            }
        ),
        "{e}"
    );
    let p = write(d, "big.nrrd", &nrrd_u8(&[2000, 2000, 2000], "raw", &[0; 8]));
    let e = read_volume(&p, &unlimited()).unwrap_err();
    assert!(
        matches!(
            e,
            ReadError::Field {
                error: FieldError::TooLarge(_),
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("2147483647"), "{e}");
    let m = fails(&write(d, "o_99999999999x99999999999x9_uint8.raw", &[0]));
    assert!(m.contains("limit"), "{m}");
    let m = fails(&write(d, "o.mha", b"NDims = 3\nDimSize = 99999999999999 99999999999 9\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n"));
    assert!(m.contains("limit"), "{m}");
}

#[test]
fn volumes_beyond_available_memory_are_refused_with_the_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "mem.nrrd",
        &nrrd("float", &[1024, 1024, 1024], "raw", "little", "", &[0; 8]),
    );
    let opts = ReadOptions {
        max_memory: Some(1 << 30),
        ..ReadOptions::default()
    };
    let e = read_volume(&p, &opts).unwrap_err();
    match &e {
        ReadError::OutOfMemory {
            needed, available, ..
        } => {
            // 4 bytes of float values and the engine's reserve per vertex.
            assert_eq!(
                *needed,
                (1u64 << 30) * (4 + flexiso::field::io::CHECK_BYTES_PER_VERTEX)
            );
            assert_eq!(*available, 1 << 30);
        }
        other => panic!("{other}"),
    }
    let m = e.to_string();
    assert!(
        m.contains(&format!(
            "{} MiB",
            1024 * (4 + flexiso::field::io::CHECK_BYTES_PER_VERTEX)
        )) && m.contains("1024 MiB")
            && m.contains("mem.nrrd"),
        "{m}"
    );
    // With the machine's real memory: refused either for memory or, on a
    // machine with more than 20 GiB free, for the missing data. Never read.
    let m = fails(&p);
    assert!(m.contains("MiB") || m.contains("truncated"), "{m}");
}

#[test]
fn a_small_file_promising_a_huge_volume_allocates_nothing_big() {
    // 10 compressed bytes promising 1.5 GB: decompression stops at the end
    // of the stream, long before the buffer grows past its first step.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let p = write(
        d,
        "huge.nrrd",
        &nrrd_u8(&[1150, 1150, 1150], "gzip", &gzip(&[1; 10])),
    );
    let t = std::time::Instant::now();
    let e = read_volume(&p, &unlimited()).unwrap_err().to_string();
    assert!(e.contains("after 10"), "{e}");
    let p = write(
        d,
        "huge2.nrrd",
        &nrrd_u8(&[1150, 1150, 1150], "bzip2", &bzip2(&[1; 10])),
    );
    let e = read_volume(&p, &unlimited()).unwrap_err().to_string();
    assert!(e.contains("after 10"), "{e}");
    let p = write(
        d,
        "huge3.nrrd",
        &nrrd_u8(&[1150, 1150, 1150], "raw", &[1; 10]),
    );
    let e = read_volume(&p, &unlimited()).unwrap_err().to_string();
    assert!(e.contains("only 10"), "{e}");
    let p = write(
        d,
        "huge4.nrrd",
        &nrrd_u8(&[1150, 1150, 1150], "ascii", b"1 2 3"),
    );
    let e = read_volume(&p, &unlimited()).unwrap_err().to_string();
    assert!(e.contains("truncated"), "{e}");
    assert!(t.elapsed().as_secs_f64() < 2.0, "took {:?}", t.elapsed());
}

#[test]
fn unknown_types_and_encodings_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = fails(&write(
        d,
        "u.nrrd",
        &nrrd("complex", &[2], "raw", "little", "", &[0; 8]),
    ));
    assert!(m.contains("unknown") && m.contains("complex"), "{m}");
    let m = fails(&write(d, "u2.nrrd", &nrrd_u8(&[2], "hex", b"0102")));
    assert!(m.contains("encoding") && m.contains("hex"), "{m}");
    let m = fails(&write(
        d,
        "u3.nrrd",
        &nrrd("short", &[2], "raw", "middle", "", &[0; 4]),
    ));
    assert!(m.contains("endian"), "{m}");
    let m = fails(&write(
        d,
        "u4.nrrd",
        &nrrd("short", &[2], "raw", "", "", &[0; 4]),
    ));
    assert!(m.contains("missing 'endian'"), "{m}");
    let m = fails(&write(
        d,
        "u.mha",
        b"NDims = 1\nDimSize = 2\nElementType = MET_FOO\nElementDataFile = LOCAL\nab",
    ));
    assert!(m.contains("MET_FOO"), "{m}");
    let m = fails(&write(
        d,
        "u.vtk",
        &vtk_legacy([2, 1, 1], "bit", false, &[0]),
    ));
    assert!(m.contains("bit"), "{m}");
    let m = fails(&write(
        d,
        "u.nii",
        &nifti_header([2, 1, 1], 32, 64, [1.0; 3], 0.0, 0.0, false),
    ));
    assert!(m.contains("datatype 32"), "{m}");
    let m = fails(&write(d, "u_2x1x1_complex64.raw", &[0; 16]));
    assert!(m.contains("NAME_XxYxZ_TYPE"), "{m}");
    let p = write(d, "u.bin", &[0; 2]);
    let opts = ReadOptions {
        raw: Some(RawLayout {
            dims: [2, 1, 1],
            scalar_type: "quaternion".into(),
            big_endian: false,
        }),
        ..ReadOptions::default()
    };
    let m = read_volume(&p, &opts).unwrap_err().to_string();
    assert!(m.contains("quaternion") && m.contains("u.bin"), "{m}");
    let vti = "<VTKFile type=\"ImageData\" compressor=\"vtkZstdDataCompressor\"><ImageData WholeExtent=\"0 0 0 0 0 0\"><Piece><PointData><DataArray type=\"UInt8\" format=\"binary\">AQAAAAE=</DataArray></PointData></Piece></ImageData></VTKFile>";
    let m = fails(&write(d, "u.vti", vti.as_bytes()));
    assert!(m.contains("vtkZstdDataCompressor"), "{m}");
}

#[test]
fn corrupt_compressed_data_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut gz = gzip(&(0..64u8).collect::<Vec<_>>());
    let mid = gz.len() / 2;
    gz[mid..].iter_mut().for_each(|b| *b ^= 0x5a);
    let m = fails(&write(d, "c.nrrd", &nrrd_u8(&[4, 4, 4], "gzip", &gz)));
    assert!(m.contains("gzip"), "{m}");
    let m = fails(&write(
        d,
        "c2.nrrd",
        &nrrd_u8(&[4, 4, 4], "gzip", b"this is not gzip at all"),
    ));
    assert!(m.contains("corrupt gzip"), "{m}");
    let m = fails(&write(
        d,
        "c3.nrrd",
        &nrrd_u8(&[4, 4, 4], "bzip2", b"BZh9 not really"),
    ));
    assert!(m.contains("bzip2"), "{m}");
    let m = fails(&write(d, "c.nii.gz", b"\x1f\x8bgarbage garbage garbage"));
    assert!(m.contains("gzip"), "{m}");
    write(d, "c.zraw", b"not zlib");
    let m = fails(&write(d, "c.mhd", b"NDims = 1\nDimSize = 4\nElementType = MET_UCHAR\nCompressedData = True\nElementDataFile = c.zraw\n"));
    assert!(m.contains("zlib"), "{m}");
}

#[test]
fn binary_garbage_headers_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let garbage: Vec<u8> = (0..4000u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    for name in [
        "g.nrrd", "g.nhdr", "g.mha", "g.mhd", "g.vtk", "g.vti", "g.nii", "g.nii.gz", "g.hdr",
        "g.dat", "g.png", "g.tif",
    ] {
        let m = fails(&write(d, name, &garbage));
        assert!(!m.is_empty());
    }
    let m = fails(&write(d, "g.nrrd", &garbage));
    assert!(m.contains("not a NRRD file"), "{m}");
    let mut b = b"NRRD0004\ntype: uint8\n".to_vec();
    b.extend_from_slice(&garbage);
    let m = fails(&write(d, "g2.nrrd", &b));
    assert!(m.contains("not text"), "{m}");
    let m = fails(&write(d, "g.dat", &garbage));
    assert!(m.contains("unknown volume format"), "{m}");
    let m = fails(&write(d, "empty.nrrd", b""));
    assert!(m.contains("not a NRRD"), "{m}");
}

#[test]
fn directories_missing_files_and_missing_data_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let empty = d.join("empty_folder");
    std::fs::create_dir(&empty).unwrap();
    let m = fails(&empty);
    assert!(m.contains("directory"), "{m}");
    let m = fails(&d.join("no_such.nrrd"));
    assert!(m.contains("No such file"), "{m}");
    let m = fails(&write(
        d,
        "lost.nhdr",
        b"NRRD0004\ntype: uint8\ndimension: 1\nsizes: 4\nencoding: raw\ndata file: lost.raw\n",
    ));
    assert!(m.contains("lost.raw") && m.contains("No such file"), "{m}");
    std::fs::create_dir(d.join("dir.raw")).unwrap();
    let m = fails(&write(
        d,
        "dirdata.nhdr",
        b"NRRD0004\ntype: uint8\ndimension: 1\nsizes: 4\nencoding: raw\ndata file: dir.raw\n",
    ));
    assert!(m.contains("directory"), "{m}");
    // A folder of slices of different sizes.
    let s = d.join("slices");
    std::fs::create_dir(&s).unwrap();
    image::GrayImage::new(4, 4).save(s.join("a1.png")).unwrap();
    image::GrayImage::new(4, 5).save(s.join("a2.png")).unwrap();
    let m = read(&s).unwrap_err().to_string();
    assert!(m.contains("a2.png") && m.contains("4x5"), "{m}");
    // A colour slice.
    let c = d.join("colour");
    std::fs::create_dir(&c).unwrap();
    image::RgbImage::new(4, 4).save(c.join("a1.png")).unwrap();
    let m = read(&c).unwrap_err().to_string();
    assert!(m.contains("grayscale"), "{m}");
}

#[test]
fn unreadable_files_are_named() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "locked.nrrd", &nrrd_u8(&[2], "raw", &[1, 2]));
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o000)).unwrap();
    if std::fs::File::open(&p).is_ok() {
        eprintln!("skipped: running as root, permissions do not stop reading");
        return;
    }
    let m = fails(&p);
    assert!(m.contains("Permission denied"), "{m}");
}

#[test]
fn nan_and_infinity_are_refused_or_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let vals = [
        1.0f32,
        f32::NAN,
        3.0,
        f32::INFINITY,
        -2.0,
        5.0,
        f32::NEG_INFINITY,
        0.5,
    ];
    let data: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
    let p = write(
        dir.path(),
        "nan.nrrd",
        &nrrd("float", &[2, 2, 2], "raw", "little", "", &data),
    );
    let e = read(&p).unwrap_err();
    assert!(
        matches!(
            e,
            ReadError::Field {
                error: FieldError::NonFinite {
                    count: 3,
                    first: 1,
                    x: 1,
                    y: 0,
                    z: 0
                },
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("nan.nrrd"));
    let min = read_volume(
        &p,
        &ReadOptions {
            nan: NanPolicy::Min,
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(
        min.field.values(),
        &Values::F32(vec![1.0, -2.0, 3.0, -2.0, -2.0, 5.0, -2.0, 0.5])
    );
    assert_eq!(min.warnings.len(), 1);
    assert!(
        min.warnings[0].contains("3 NaN") && min.warnings[0].contains("x=1 y=0 z=0"),
        "{:?}",
        min.warnings
    );
    let max = read_volume(
        &p,
        &ReadOptions {
            nan: NanPolicy::Max,
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(
        max.field.values(),
        &Values::F32(vec![1.0, 5.0, 3.0, 5.0, -2.0, 5.0, 5.0, 0.5])
    );
    // All non-finite: nothing to replace with.
    let data: Vec<u8> = [f64::NAN; 2].iter().flat_map(|v| v.to_le_bytes()).collect();
    let p = write(
        dir.path(),
        "allnan.nrrd",
        &nrrd("double", &[2], "raw", "little", "", &data),
    );
    let e = read_volume(
        &p,
        &ReadOptions {
            nan: NanPolicy::Max,
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("every value"), "{e}");
}

#[test]
fn reading_a_shrinking_file_is_a_truncation_error() {
    // The data file of a detached header changes between two reads; the
    // second read reports the truncation. (A file shrinking during one read,
    // after the size check, is covered by the unit test
    // `short_stream_is_truncation_not_panic` in src/field/io/data.rs.)
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "live.raw", &[0; 64]);
    let h = write(
        d,
        "live.nhdr",
        b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: live.raw\n",
    );
    assert!(read(&h).is_ok());
    write(d, "live.raw", &[0; 40]);
    let m = read(&h).unwrap_err().to_string();
    assert!(m.contains("live.raw") && m.contains("truncated"), "{m}");
}
