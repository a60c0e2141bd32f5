//! `flexiso render` end to end: the binary writes a PNG of the contours, and
//! refuses bad requests with a message. Rendering needs an adapter: those
//! checks are skipped without one unless `FLEXISO_REQUIRE_GPU=1`.

mod common;

use common::flexiso;
use flexiso::field::synthetic::Synthetic;
use flexiso::progress::Progress;
use flexiso::render::DEFAULT_BACKGROUND;
use flexiso::tree::ContourTree;

fn drawn_fraction(img: &image::RgbaImage) -> f32 {
    let bg = DEFAULT_BACKGROUND.map(|c| (c * 255.0).round() as i32);
    let drawn = img
        .pixels()
        .filter(|p| {
            p.0.iter()
                .zip(bg)
                .any(|(a, b)| (i32::from(*a) - b).abs() > 1)
        })
        .count();
    drawn as f32 / (img.width() * img.height()) as f32
}

#[test]
fn render_writes_a_png_of_all_contours_and_of_one_arc() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let all = dir.path().join("all.png");
    let out = flexiso(&[
        "render",
        "synthetic:32",
        "--out",
        all.to_str().expect("utf-8 path"),
        "--size",
        "320x240",
        "--iso",
        "0.45",
    ]);
    assert!(out.success(), "{}", out.stderr);
    let img = image::open(&all).expect("png").to_rgba8();
    assert_eq!(img.dimensions(), (320, 240));
    let f = drawn_fraction(&img);
    assert!(f > 0.02 && f < 0.6, "drawn fraction {f}");

    // One arc: the highest maximum's, by its end vertices.
    let field = Synthetic::cube(32).generate();
    let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("tree");
    let a = tree
        .arcs()
        .iter()
        .max_by(|a, b| {
            let f = |x: &flexiso::tree::Superarc| field.value(tree.node(x.upper).vertex);
            f(a).total_cmp(&f(b))
        })
        .expect("arcs");
    let (upper, lower) = (tree.node(a.upper).vertex, tree.node(a.lower).vertex);
    let one = dir.path().join("one.png");
    let out = flexiso(&[
        "render",
        "synthetic:32",
        "--out",
        one.to_str().expect("utf-8 path"),
        "--size",
        "200x150",
        "--arc",
        &format!("{upper}:{lower}"),
    ]);
    assert!(out.success(), "{}", out.stderr);
    let img = image::open(&one).expect("png").to_rgba8();
    assert_eq!(img.dimensions(), (200, 150));
    assert!(drawn_fraction(&img) > 0.001);
}

#[test]
fn render_refuses_bad_requests_with_a_message() {
    // None of these gets as far as the GPU.
    let cases: [(&[&str], &str); 4] = [
        (&["render", "synthetic:8", "--size", "big"], "WxH"),
        (&["render", "synthetic:8", "--arc", "7"], "UPPER:LOWER"),
        (&["render", "synthetic:8", "--arc", "1:2"], "no superarc"),
        (&["render", "synthetic:8", "--iso", "99"], "outside"),
    ];
    for (args, expect) in cases {
        let out = flexiso(args);
        let err = &out.stderr;
        assert!(!out.success(), "{args:?} succeeded");
        assert!(err.contains(expect), "{args:?}: {err}");
    }
}

/// How far `img` is from the reference picture `name`
/// (tests/render_reference/, drawn by the renderer before the compact
/// vertex format: 24-byte vertices, 32-bit indices): the mean absolute
/// difference per channel, and the fraction of pixels off by more than 24
/// levels in some channel (edges that moved by a sample).
fn distance_to_reference(img: &image::RgbaImage, name: &str) -> (f64, f64) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/render_reference")
        .join(name);
    let want = image::open(&path).expect("reference picture").to_rgba8();
    assert_eq!(img.dimensions(), want.dimensions(), "{name}: size");
    let mut sum = 0u64;
    let mut far = 0usize;
    for (a, b) in img.pixels().zip(want.pixels()) {
        let d =
            a.0.iter()
                .zip(b.0)
                .map(|(x, y)| (i32::from(*x) - i32::from(y)).unsigned_abs());
        sum += d.clone().map(u64::from).sum::<u64>();
        far += usize::from(d.max().unwrap_or(0) > 24);
    }
    let pixels = (img.width() * img.height()) as f64;
    (sum as f64 / (4.0 * pixels), far as f64 / pixels)
}

/// The compact vertex format (quantised positions, octahedral normals,
/// 16-bit index runs) draws what the 24-byte format drew: the same scenes
/// through `flexiso render`, pixel-close to pictures made before it.
#[test]
fn compact_meshes_render_pixel_close_to_the_full_precision_pictures() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let mut cases = vec![
        ("synthetic:40", "0.45", "synthetic40_iso045.png"),
        ("synthetic:128", "0.3", "synthetic128_iso03.png"),
    ];
    let neghip = common::dataset("neghip.nrrd")
        .map(|p| p.to_str().expect("utf-8 path").to_owned())
        .unwrap_or_default();
    if !neghip.is_empty() {
        cases.push((&neghip, "80", "neghip_iso80.png"));
    }
    for (input, iso, reference) in cases {
        let out = dir.path().join(reference);
        let o = flexiso(&[
            "render",
            input,
            "--iso",
            iso,
            "--size",
            "320x240",
            "--out",
            out.to_str().expect("utf-8 path"),
        ]);
        assert!(o.success(), "{}", o.stderr);
        let img = image::open(&out).expect("a png").to_rgba8();
        let (mean, far) = distance_to_reference(&img, reference);
        eprintln!(
            "{reference}: mean difference {mean:.3} levels, {:.3} % pixels far",
            100.0 * far
        );
        assert!(mean < 0.5, "{reference}: mean difference {mean}");
        assert!(far < 0.002, "{reference}: {far} of the pixels differ");
    }
}
