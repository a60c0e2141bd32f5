//! Fuzz-style property tests: valid files of every format, mutated byte by
//! byte (set, insert, delete, insert a long run of digits, truncate), and
//! plain random bytes under every extension. Each read must give a valid
//! volume or a one-line error naming the file; never a panic.
#![allow(clippy::unwrap_used)]

mod common;
use common::formats::*;

use base64::Engine as _;
use flexiso::field::io::{ReadOptions, read_volume};
use proptest::prelude::*;
use std::path::Path;

/// Valid seed files: (file name, bytes).
fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    let vals = reference("int16", 24);
    let le = encode(&vals, "int16", false);
    let be = encode(&vals, "int16", true);
    let f32s = encode(&reference("float32", 24), "float32", false);
    let mut out = vec![
        (
            "a.nrrd",
            nrrd(
                "short",
                &[2, 3, 4],
                "raw",
                "little",
                "spacings: 1 2 3\n",
                &le,
            ),
        ),
        (
            "b.nrrd",
            nrrd(
                "float",
                &[2, 3, 4],
                "gzip",
                "little",
                "space directions: (1,0,0) (0,2,0) (0,0,3)\n",
                &gzip(&f32s),
            ),
        ),
        (
            "c.nrrd",
            nrrd(
                "int16",
                &[6, 4],
                "bzip2",
                "big",
                "byte skip: 0\nline skip: 0\n",
                &bzip2(&be),
            ),
        ),
        (
            "d.nrrd",
            nrrd(
                "uint8",
                &[2, 3, 4],
                "ascii",
                "",
                "",
                b"1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24",
            ),
        ),
        ("n_2x3x4_int16.raw", le.clone()),
        ("a.vtk", vtk_legacy([2, 3, 4], "short", false, &be)),
        (
            "b.vtk",
            vtk_legacy(
                [2, 3, 4],
                "float",
                true,
                b"1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24",
            ),
        ),
    ];
    let mut mha = b"ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = False\nElementSpacing = 1 2 3\nDimSize = 2 3 4\nElementType = MET_SHORT\nHeaderSize = 0\nElementDataFile = LOCAL\n".to_vec();
    mha.extend_from_slice(&le);
    out.push(("a.mha", mha));
    let mut mha = b"NDims = 3\nCompressedData = True\nDimSize = 2 3 4\nElementType = MET_SHORT\nElementDataFile = LOCAL\n".to_vec();
    mha.extend_from_slice(&zlib(&le));
    out.push(("b.mha", mha));
    let mut nii = nifti_header([2, 3, 4], 4, 16, [1.0, 2.0, 3.0], 2.0, 1.0, false);
    nii.extend_from_slice(&le);
    out.push(("a.nii", nii.clone()));
    out.push(("b.nii.gz", gzip(&nii)));
    let mut nii = nifti_header([2, 3, 4], 4, 16, [1.0, 2.0, 3.0], 0.0, 0.0, true);
    nii.extend_from_slice(&be);
    out.push(("c.nii", nii));
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let head = "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt32\"";
    let body = "><ImageData WholeExtent=\"0 1 0 2 0 3\" Spacing=\"1 2 3\"><Piece Extent=\"0 1 0 2 0 3\"><PointData Scalars=\"v\">";
    let vti = format!(
        "{head}{body}<DataArray type=\"Int16\" Name=\"v\" format=\"binary\">{}{}</DataArray></PointData></Piece></ImageData></VTKFile>",
        b64(&48u32.to_le_bytes()),
        b64(&le)
    );
    out.push(("a.vti", vti.into_bytes()));
    // UInt64 headers, big-endian, one base64 run, appended uncompressed.
    let head64 = "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"BigEndian\" header_type=\"UInt64\"";
    let mut joined = 48u64.to_be_bytes().to_vec();
    joined.extend_from_slice(&be);
    let vti = format!(
        "{head64}{body}<DataArray type=\"Int16\" Name=\"v\" format=\"binary\">{}</DataArray></PointData></Piece></ImageData></VTKFile>",
        b64(&joined)
    );
    out.push(("c.vti", vti.into_bytes()));
    let mut vti = format!(
        "{head64}{body}<DataArray type=\"Int16\" Name=\"v\" format=\"appended\" offset=\"0\"/></PointData></Piece></ImageData><AppendedData encoding=\"raw\">_"
    )
    .into_bytes();
    vti.extend_from_slice(&joined);
    vti.extend_from_slice(b"</AppendedData></VTKFile>");
    out.push(("d.vti", vti));
    let comp = zlib(&le);
    let mut app = Vec::new();
    for w in [1u32, 48, 48, comp.len() as u32] {
        app.extend_from_slice(&w.to_le_bytes());
    }
    app.extend_from_slice(&comp);
    let mut vti = format!(
        "{head} compressor=\"vtkZLibDataCompressor\"{body}<DataArray type=\"Int16\" Name=\"v\" format=\"appended\" offset=\"0\"/></PointData></Piece></ImageData><AppendedData encoding=\"raw\">_"
    )
    .into_bytes();
    vti.extend_from_slice(&app);
    vti.extend_from_slice(b"</AppendedData></VTKFile>");
    out.push(("b.vti", vti));
    out
}

/// Reads `path` with a memory cap (mutated sizes must not make the test
/// machine allocate gigabytes) and checks the outcome is sane.
fn read_sanely(path: &Path) -> Result<(), TestCaseError> {
    let opts = ReadOptions {
        max_memory: Some(256 << 20),
        ..ReadOptions::default()
    };
    match read_volume(path, &opts) {
        Ok(v) => {
            let [x, y, z] = v.field.dims();
            prop_assert_eq!(v.field.len(), x * y * z);
            prop_assert!(v.field.spacing().iter().all(|s| s.is_finite() && *s > 0.0));
        }
        Err(e) => {
            let m = e.to_string();
            prop_assert!(!m.contains('\n'), "multi-line error: {}", m);
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            prop_assert!(
                m.contains(&name) || m.contains("data file"),
                "error does not name the file: {}",
                m
            );
        }
    }
    Ok(())
}

#[test]
fn seeds_are_valid() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in seeds() {
        let p = write(dir.path(), name, &bytes);
        let v = read(&p).unwrap_or_else(|e| panic!("seed {name}: {e}"));
        assert_eq!(v.field.len(), 24, "{name}");
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    Set(usize, u8),
    Insert(usize, u8),
    Delete(usize),
    Digits(usize),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Mutation::Set(p, b)),
        1 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Mutation::Insert(p, b)),
        1 => any::<usize>().prop_map(Mutation::Delete),
        1 => any::<usize>().prop_map(Mutation::Digits),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation, header_bias: bool) {
    if bytes.is_empty() {
        return;
    }
    // Most mutations land in the header, where the parsers are.
    let span = if header_bias {
        bytes.len().min(400)
    } else {
        bytes.len()
    };
    let at = |p: usize| p % span;
    match *m {
        Mutation::Set(p, b) => {
            let i = at(p);
            bytes[i] = b;
        }
        Mutation::Insert(p, b) => bytes.insert(at(p), b),
        Mutation::Delete(p) => {
            bytes.remove(at(p));
        }
        Mutation::Digits(p) => {
            let i = at(p);
            bytes.splice(i..i, b"99999999999".iter().copied());
        }
        Mutation::Truncate(p) => bytes.truncate(p % bytes.len()),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: fuzz_cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_files_never_panic(
        seed in 0usize..17,
        muts in proptest::collection::vec(mutation(), 1..6),
        header_bias in proptest::bool::weighted(0.8),
    ) {
        let seeds = seeds();
        let (name, mut bytes) = seeds[seed % seeds.len()].clone();
        for m in &muts {
            apply(&mut bytes, m, header_bias);
        }
        let dir = tempfile::tempdir().unwrap();
        read_sanely(&write(dir.path(), name, &bytes))?;
    }

    #[test]
    fn random_bytes_never_panic(
        bytes in proptest::collection::vec(any::<u8>(), 0..1200),
        prefix in 0usize..8,
        ext in 0usize..12,
    ) {
        // Random data, optionally behind a valid magic so the parser gets
        // past its first check.
        let magic: &[&[u8]] = &[b"", b"NRRD0004\n", b"# vtk DataFile Version 3.0\n", b"<VTKFile type=\"ImageData\">", b"NDims = 3\n", b"\x5c\x01\x00\x00", b"\x1f\x8b", b"NRRD0004\ntype: uint8\ndimension: 3\n"];
        let names = ["f.nrrd", "f.nhdr", "f.mha", "f.mhd", "f.vtk", "f.vti", "f.nii", "f.nii.gz", "f.hdr", "f_4x4x4_uint8.raw", "f.png", "f.bin"];
        let mut b = magic[prefix].to_vec();
        b.extend_from_slice(&bytes);
        let dir = tempfile::tempdir().unwrap();
        read_sanely(&write(dir.path(), names[ext], &b))?;
    }
}

/// Cases per property: 768, or `IO_FUZZ_CASES` for a longer hunt.
fn fuzz_cases() -> u32 {
    std::env::var("IO_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(768)
}
