//! NRRD reader: every type, alias, encoding and byte order round-trips;
//! spacing from `spacings` and `space directions`; detached headers; skips;
//! and every file of the shared data folder decodes to the manifest's
//! values (skipped when the folder is absent).
#![allow(clippy::unwrap_used)]

mod common;
use common::formats::*;

use flexiso::field::Values;

#[test]
fn every_type_encoding_and_endian_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [5usize, 4, 3];
    for ty in TYPES {
        let vals = reference(ty, 60);
        for (enc, big) in [
            ("raw", false),
            ("raw", true),
            ("gzip", false),
            ("bzip2", true),
            ("gz", true),
            ("bz2", false),
        ] {
            let bytes = encode(&vals, ty, big);
            let data = match enc {
                "gzip" | "gz" => gzip(&bytes),
                "bzip2" | "bz2" => bzip2(&bytes),
                _ => bytes,
            };
            let endian = if big { "big" } else { "little" };
            let p = write(
                dir.path(),
                &format!("{ty}_{enc}_{endian}.nrrd"),
                &nrrd(ty, &dims, enc, endian, "", &data),
            );
            let v = read(&p).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(v.field.dims(), dims);
            assert_eq!(v.field.values().type_name(), stored(ty), "{ty}");
            assert_eq!(v.scalar_type.name(), ty);
            assert_eq!(as_f64(v.field.values()), vals, "{ty} {enc} {endian}");
        }
        // ASCII needs no endian.
        let text: Vec<String> = vals.iter().map(|v| v.to_string()).collect();
        let p = write(
            dir.path(),
            &format!("{ty}_ascii.nrrd"),
            &nrrd(ty, &dims, "ascii", "", "", text.join("\n").as_bytes()),
        );
        assert_eq!(as_f64(read(&p).unwrap().field.values()), vals, "{ty} ascii");
    }
}

#[test]
fn type_aliases_are_accepted() {
    let dir = tempfile::tempdir().unwrap();
    for (alias, ty) in [
        ("unsigned char", "uint8"),
        ("uchar", "uint8"),
        ("signed char", "int8"),
        ("short", "int16"),
        ("short int", "int16"),
        ("ushort", "uint16"),
        ("unsigned short int", "uint16"),
        ("int", "int32"),
        ("uint", "uint32"),
        ("float", "float32"),
        ("double", "float64"),
        ("long long", "int64"),
        ("ulonglong", "uint64"),
        ("int64_t", "int64"),
    ] {
        let vals = reference(ty, 8);
        let p = write(
            dir.path(),
            "a.nrrd",
            &nrrd(
                alias,
                &[2, 2, 2],
                "raw",
                "little",
                "",
                &encode(&vals, ty, false),
            ),
        );
        let v = read(&p).unwrap_or_else(|e| panic!("{alias}: {e}"));
        assert_eq!(v.scalar_type.name(), ty, "{alias}");
        assert_eq!(as_f64(v.field.values()), vals, "{alias}");
    }
}

#[test]
fn int64_beyond_2_pow_53_converts_to_nearest_f64() {
    let dir = tempfile::tempdir().unwrap();
    let big = (1i64 << 53) + 1;
    let mut data = Vec::new();
    for x in [big, -big, i64::MAX, i64::MIN] {
        data.extend_from_slice(&x.to_le_bytes());
    }
    let p = write(
        dir.path(),
        "i64.nrrd",
        &nrrd("int64", &[4], "raw", "little", "", &data),
    );
    let v = read(&p).unwrap();
    assert_eq!(v.field.dims(), [4, 1, 1]);
    assert_eq!(
        v.field.values(),
        &Values::F64(vec![
            big as f64,
            -big as f64,
            i64::MAX as f64,
            i64::MIN as f64
        ])
    );
}

#[test]
fn two_dimensional_nrrd_has_depth_one() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("uint16", 12);
    let p = write(
        dir.path(),
        "img.nrrd",
        &nrrd(
            "uint16",
            &[4, 3],
            "raw",
            "big",
            "spacings: 0.5 2\n",
            &encode(&vals, "uint16", true),
        ),
    );
    let v = read(&p).unwrap();
    assert_eq!(v.field.dims(), [4, 3, 1]);
    assert_eq!(v.field.spacing(), [0.5, 2.0, 1.0]);
    assert_eq!(as_f64(v.field.values()), vals);
}

#[test]
fn spacing_comes_from_spacings_or_direction_norms() {
    let dir = tempfile::tempdir().unwrap();
    let data = vec![7u8; 8];
    let p = write(
        dir.path(),
        "s.nrrd",
        &nrrd(
            "uint8",
            &[2, 2, 2],
            "raw",
            "",
            "spacings: 0.5 nan 3\n",
            &data,
        ),
    );
    assert_eq!(read(&p).unwrap().field.spacing(), [0.5, 1.0, 3.0]);
    let p = write(
        dir.path(),
        "d.nrrd",
        &nrrd(
            "uint8",
            &[2, 2, 2],
            "raw",
            "",
            "space: left-posterior-superior\nspace directions: (0,0.5,0) (3,4,0) (0,0,-2)\nspace origin: (1,2,3)\n",
            &data,
        ),
    );
    assert_eq!(read(&p).unwrap().field.spacing(), [0.5, 5.0, 2.0]);
}

#[test]
fn comments_key_values_and_crlf_are_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = b"NRRD0005\r\n# comment\r\nmy key:=my: value\r\ntype: uint8\r\ndimension: 3\r\nsizes: 2 1 1\r\nencoding: raw\r\nkinds: domain domain domain\r\n\r\n".to_vec();
    b.extend_from_slice(&[3, 9]);
    let p = write(dir.path(), "crlf.nrrd", &b);
    assert_eq!(read(&p).unwrap().field.values(), &Values::U8(vec![3, 9]));
}

#[test]
fn detached_header_reads_its_data_file() {
    let dir = tempfile::tempdir().unwrap();
    let vals = reference("float32", 24);
    let raw = encode(&vals, "float32", false);
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    write(&dir.path().join("sub"), "v.raw.gz", &gzip(&raw));
    let h = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 3 4\nencoding: gzip\nendian: little\ndata file: sub/v.raw.gz\n";
    let p = write(dir.path(), "v.nhdr", h.as_bytes());
    let v = read(&p).unwrap();
    assert_eq!(v.format, "NRRD detached (gzip)");
    assert_eq!(as_f64(v.field.values()), vals);
    // The same with the raw data behind a line skip and a byte skip.
    let mut data = b"line one\nline two\n".to_vec();
    data.extend_from_slice(b"XYZ");
    data.extend_from_slice(&raw);
    write(dir.path(), "v.dat", &data);
    let h = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 3 4\nencoding: raw\nendian: little\nline skip: 2\nbyte skip: 3\ndatafile: v.dat\n";
    let p = write(dir.path(), "w.nhdr", h.as_bytes());
    assert_eq!(as_f64(read(&p).unwrap().field.values()), vals);
    // byte skip -1: the data ends the file.
    let h = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 3 4\nencoding: raw\nendian: little\nbyte skip: -1\ndata file: v.dat\n";
    let p = write(dir.path(), "x.nhdr", h.as_bytes());
    assert_eq!(as_f64(read(&p).unwrap().field.values()), vals);
}

#[test]
fn byte_skip_applies_after_decompression() {
    let dir = tempfile::tempdir().unwrap();
    let mut raw = vec![0xAAu8; 5];
    raw.extend_from_slice(&[1, 2, 3, 4]);
    let p = write(
        dir.path(),
        "bs.nrrd",
        &nrrd("uint8", &[4], "gzip", "", "byte skip: 5\n", &gzip(&raw)),
    );
    assert_eq!(
        read(&p).unwrap().field.values(),
        &Values::U8(vec![1, 2, 3, 4])
    );
}

#[test]
fn shared_data_decodes_to_manifest_values() {
    let Some(data) = common::data_dir() else {
        return;
    };
    let manifest = std::fs::read_to_string(data.join("MANIFEST.tsv")).unwrap();
    let mut checked = 0;
    for line in manifest.lines().skip(1) {
        let cols: Vec<&str> = line.split('\t').collect();
        let (file, dims, ty, hash) = (cols[0], cols[1], cols[2], cols[4]);
        let dims: Vec<usize> = dims
            .split_whitespace()
            .map(|d| d.parse().unwrap())
            .collect();
        let v = read(&data.join(file)).unwrap();
        assert_eq!(v.field.dims().to_vec(), dims, "{file}");
        let want = if ty == "float" { "float32" } else { ty };
        assert_eq!(v.field.values().type_name(), want, "{file}");
        assert_eq!(values_hash(v.field.values()), hash, "{file}");
        checked += 1;
    }
    // Every row was checked above; how many there are is the folder's
    // business, not the reader's.
    assert!(checked > 0, "MANIFEST.tsv lists no volume");
}
