//! Files for the reader tests: a reference volume, encoders for every
//! scalar type, compressors, writers for each format, and SHA-256 (to check
//! decoded values against the data folder's MANIFEST.tsv).

use flexiso::field::Values;
use flexiso::field::io::{ReadError, ReadOptions, Volume, read_volume};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Every scalar type by its canonical name.
pub const TYPES: [&str; 10] = [
    "uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64", "float32", "float64",
];

/// Reference values for a type: a pattern that exercises sign and range,
/// exact in every type (small integers, negative for signed types).
pub fn reference(ty: &str, n: usize) -> Vec<f64> {
    let signed = ty.starts_with("int") || ty.starts_with("float");
    (0..n)
        .map(|i| {
            let v = ((i * 37 + 11) % 101) as f64;
            if signed { v - 50.0 } else { v }
        })
        .collect()
}

/// The bytes of `vals` in type `ty` and the given byte order.
pub fn encode(vals: &[f64], ty: &str, big: bool) -> Vec<u8> {
    let mut out = Vec::new();
    macro_rules! put {
        ($t:ty) => {
            for &v in vals {
                let x = v as $t;
                out.extend_from_slice(&if big {
                    x.to_be_bytes()
                } else {
                    x.to_le_bytes()
                });
            }
        };
    }
    match ty {
        "uint8" => put!(u8),
        "int8" => put!(i8),
        "uint16" => put!(u16),
        "int16" => put!(i16),
        "uint32" => put!(u32),
        "int32" => put!(i32),
        "uint64" => put!(u64),
        "int64" => put!(i64),
        "float32" => put!(f32),
        "float64" => put!(f64),
        _ => panic!("type {ty}"),
    }
    out
}

/// The values of a volume as f64.
pub fn as_f64(v: &Values) -> Vec<f64> {
    (0..v.len()).map(|i| v.get(i)).collect()
}

/// The type a file type is stored as.
pub fn stored(ty: &str) -> &'static str {
    match ty {
        "uint8" => "uint8",
        "int8" => "int8",
        "uint16" => "uint16",
        "int16" => "int16",
        "uint32" => "uint32",
        "int32" => "int32",
        "float32" => "float32",
        _ => "float64",
    }
}

pub fn gzip(b: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

pub fn zlib(b: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

pub fn bzip2(b: &[u8]) -> Vec<u8> {
    let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::default());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

pub fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

pub fn read(p: &Path) -> Result<Volume, ReadError> {
    read_volume(p, &ReadOptions::default())
}

/// The error message for a file that must fail.
pub fn fails(p: &Path) -> String {
    match read(p) {
        Ok(v) => panic!("{} should fail but read {:?}", p.display(), v.field.dims()),
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.contains(&p.file_name().unwrap().to_string_lossy().to_string()),
                "error does not name the file: {msg}"
            );
            assert!(!msg.contains('\n'), "error is not one line: {msg}");
            msg
        }
    }
}

/// An attached NRRD file's bytes.
pub fn nrrd(
    ty: &str,
    sizes: &[usize],
    encoding: &str,
    endian: &str,
    extra: &str,
    data: &[u8],
) -> Vec<u8> {
    let sizes: Vec<String> = sizes.iter().map(|s| s.to_string()).collect();
    let mut h = format!(
        "NRRD0004\n# test\ntype: {ty}\ndimension: {}\nsizes: {}\nencoding: {encoding}\n",
        sizes.len(),
        sizes.join(" ")
    );
    if !endian.is_empty() {
        h += &format!("endian: {endian}\n");
    }
    h += extra;
    h += "\n";
    let mut b = h.into_bytes();
    b.extend_from_slice(data);
    b
}

/// A NIfTI-1 header (348 bytes) plus 4 bytes of extension flag.
pub fn nifti_header(
    dims: [usize; 3],
    datatype: i16,
    bitpix: i16,
    spacing: [f32; 3],
    slope: f32,
    inter: f32,
    big: bool,
) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let i32b = |v: i32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let i16b = |v: i16| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let f32b = |v: f32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    h[0..4].copy_from_slice(&i32b(348));
    let dim = [
        3i16,
        dims[0] as i16,
        dims[1] as i16,
        dims[2] as i16,
        1,
        1,
        1,
        1,
    ];
    for (i, d) in dim.iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&i16b(*d));
    }
    h[70..72].copy_from_slice(&i16b(datatype));
    h[72..74].copy_from_slice(&i16b(bitpix));
    let pix = [
        1.0f32, spacing[0], spacing[1], spacing[2], 1.0, 1.0, 1.0, 1.0,
    ];
    for (i, p) in pix.iter().enumerate() {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&f32b(*p));
    }
    h[108..112].copy_from_slice(&f32b(352.0));
    h[112..116].copy_from_slice(&f32b(slope));
    h[116..120].copy_from_slice(&f32b(inter));
    h[344..348].copy_from_slice(b"n+1\0");
    h
}

/// A legacy VTK STRUCTURED_POINTS file.
pub fn vtk_legacy(dims: [usize; 3], vtk_type: &str, ascii: bool, data: &[u8]) -> Vec<u8> {
    let n = dims[0] * dims[1] * dims[2];
    let mut b = format!(
        "# vtk DataFile Version 3.0\ntest volume\n{}\nDATASET STRUCTURED_POINTS\nDIMENSIONS {} {} {}\nSPACING 1 2 3\nORIGIN 0 0 0\nPOINT_DATA {n}\nSCALARS values {vtk_type} 1\nLOOKUP_TABLE default\n",
        if ascii { "ASCII" } else { "BINARY" },
        dims[0],
        dims[1],
        dims[2]
    )
    .into_bytes();
    b.extend_from_slice(data);
    b
}

/// SHA-256 (FIPS 180-4), to compare decoded values with the manifest.
pub fn sha256(data: &[u8]) -> [u8; 32] {
    const K: [u32; 64] = [
        0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4,
        0xab1c5ed5, 0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe,
        0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f,
        0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7,
        0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc,
        0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b,
        0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116,
        0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
        0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
        0xc67178f2,
    ];
    let mut h: [u32; 8] = [
        0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab,
        0x5be0cd19,
    ];
    let mut msg = data.to_vec();
    let bits = (data.len() as u64) * 8;
    msg.push(0x80);
    while msg.len() % 64 != 56 {
        msg.push(0);
    }
    msg.extend_from_slice(&bits.to_be_bytes());
    for chunk in msg.chunks(64) {
        let mut w = [0u32; 64];
        for i in 0..16 {
            w[i] = u32::from_be_bytes(chunk[4 * i..4 * i + 4].try_into().unwrap());
        }
        for i in 16..64 {
            let s0 = w[i - 15].rotate_right(7) ^ w[i - 15].rotate_right(18) ^ (w[i - 15] >> 3);
            let s1 = w[i - 2].rotate_right(17) ^ w[i - 2].rotate_right(19) ^ (w[i - 2] >> 10);
            w[i] = w[i - 16]
                .wrapping_add(s0)
                .wrapping_add(w[i - 7])
                .wrapping_add(s1);
        }
        let [mut a, mut b, mut c, mut d, mut e, mut f, mut g, mut hh] = h;
        for i in 0..64 {
            let s1 = e.rotate_right(6) ^ e.rotate_right(11) ^ e.rotate_right(25);
            let ch = (e & f) ^ (!e & g);
            let t1 = hh
                .wrapping_add(s1)
                .wrapping_add(ch)
                .wrapping_add(K[i])
                .wrapping_add(w[i]);
            let s0 = a.rotate_right(2) ^ a.rotate_right(13) ^ a.rotate_right(22);
            let maj = (a & b) ^ (a & c) ^ (b & c);
            let t2 = s0.wrapping_add(maj);
            hh = g;
            g = f;
            f = e;
            e = d.wrapping_add(t1);
            d = c;
            c = b;
            b = a;
            a = t1.wrapping_add(t2);
        }
        for (x, y) in h.iter_mut().zip([a, b, c, d, e, f, g, hh]) {
            *x = x.wrapping_add(y);
        }
    }
    let mut out = [0u8; 32];
    for (i, x) in h.iter().enumerate() {
        out[4 * i..4 * i + 4].copy_from_slice(&x.to_be_bytes());
    }
    out
}

/// The first 16 hex digits of the SHA-256 of the values' little-endian
/// bytes, as MANIFEST.tsv lists them.
pub fn values_hash(v: &Values) -> String {
    let bytes: Vec<u8> = match v {
        Values::U8(x) => x.clone(),
        Values::I8(x) => x.iter().map(|b| *b as u8).collect(),
        Values::U16(x) => x.iter().flat_map(|b| b.to_le_bytes()).collect(),
        Values::I16(x) => x.iter().flat_map(|b| b.to_le_bytes()).collect(),
        Values::U32(x) => x.iter().flat_map(|b| b.to_le_bytes()).collect(),
        Values::I32(x) => x.iter().flat_map(|b| b.to_le_bytes()).collect(),
        Values::F32(x) => x.iter().flat_map(|b| b.to_le_bytes()).collect(),
        Values::F64(x) => x.iter().flat_map(|b| b.to_le_bytes()).collect(),
    };
    sha256(&bytes)[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}
