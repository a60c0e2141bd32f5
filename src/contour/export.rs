//! Writing contours to files: binary little-endian PLY, Wavefront OBJ (one
//! `o` object per contour, with normals), binary STL (triangles only,
//! facet normals) and VTK XML PolyData (`.vtp`). The format follows the
//! file's extension.
//!
//! VTP: per point the normal (`Normals`) and the value of the field there
//! (`value`: the contour's isovalue); per triangle the index of its
//! contour (`contour`, the active scalars) and its superarc (`arc`: the
//! index into the tree JSON's top-level `arcs`); as field data, per
//! contour index its name (`contour_names`), superarc (`contour_arc`) and
//! isovalue (`contour_isovalue`), and the note (`note`).
//!
//! PLY: each vertex carries its normal, a colour (`red green blue`, one
//! per contour) and the index of its contour (`int contour`); faces carry
//! only `vertex_indices`. Keeping the id on the vertices is what the
//! common readers understand: meshio reads per-face properties of binary
//! PLY wrongly (it takes them as whole columns), VTK's reader drops unknown
//! face properties but shows vertex colours, trimesh keeps both. A
//! `comment contour I NAME superarc A isovalue H` line per contour maps each
//! index to its object (e.g. `arc_UPPER_LOWER`), its superarc (the index
//! into the tree JSON's `arcs`) and its isovalue, and the note (space,
//! command) is a comment too.

use super::ContourMesh;
use std::borrow::Borrow;
use std::io::{self, Write};
use std::path::Path;
use thiserror::Error;

/// Why contours could not be written.
#[derive(Debug, Error)]
pub enum ExportError {
    /// The extension names no format we write.
    #[error("{path}: unknown mesh format (use .ply, .obj, .stl or .vtp)")]
    UnknownFormat {
        /// The file.
        path: String,
    },
    /// The file could not be written.
    #[error("{path}: cannot write: {error}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's reason (part of the message, so not a
        /// `source`: printing the chain would repeat it).
        error: io::Error,
    },
}

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Binary little-endian PLY.
    Ply,
    /// Wavefront OBJ (text).
    Obj,
    /// Binary STL.
    Stl,
    /// VTK XML PolyData (`.vtp`), binary.
    Vtp,
}

impl MeshFormat {
    /// The format a file name's extension names, if any.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "ply" => Some(Self::Ply),
            "obj" => Some(Self::Obj),
            "stl" => Some(Self::Stl),
            "vtp" => Some(Self::Vtp),
            _ => None,
        }
    }
}

/// Writes `contours` to `path`, one named object per contour (`names`
/// parallel to `contours`), in the format of its extension.
pub fn write_contours(
    path: &Path,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
) -> Result<(), ExportError> {
    write_contours_noting(path, contours, names, "")
}

/// [`write_contours`] with a line of text for the file's header (a PLY
/// `comment`, an OBJ `#` line, the start of STL's 80-byte header), e.g. the
/// coordinate space of the positions.
pub fn write_contours_noting(
    path: &Path,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    note: &str,
) -> Result<(), ExportError> {
    let format = MeshFormat::from_path(path).ok_or_else(|| ExportError::UnknownFormat {
        path: path.display().to_string(),
    })?;
    write_contours_as(path, format, contours, names, note)
}

/// [`write_contours_noting`] in a format named, whatever the extension.
pub fn write_contours_as(
    path: &Path,
    format: MeshFormat,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    note: &str,
) -> Result<(), ExportError> {
    let io_err = |error| ExportError::Io {
        path: path.display().to_string(),
        error,
    };
    crate::output::write_whole(path, |mut w| {
        write_mesh(&mut w, format, contours, names, note)
    })
    .map_err(io_err)
}

/// Writes `contours` in `format` to any writer (standard output, a
/// buffer), with `note` in the header.
pub fn write_mesh(
    w: &mut impl Write,
    format: MeshFormat,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    note: &str,
) -> io::Result<()> {
    let note: String = note.chars().filter(|c| !c.is_control()).collect();
    match format {
        MeshFormat::Ply => write_ply(w, contours, names, &note),
        MeshFormat::Obj => write_obj(w, contours, names, &note),
        MeshFormat::Stl => write_stl(w, contours, &note),
        MeshFormat::Vtp => write_vtp(w, contours, names, &note),
    }
}

/// One binary DataArray of a VTK XML file: base64 of a UInt64 byte count
/// then the little-endian data.
fn vtk_array(
    w: &mut impl Write,
    ty: &str,
    name: &str,
    comps: usize,
    data: &[u8],
) -> io::Result<()> {
    use base64::Engine as _;
    let mut raw = (data.len() as u64).to_le_bytes().to_vec();
    raw.extend_from_slice(data);
    let name = if name.is_empty() {
        String::new()
    } else {
        format!(" Name=\"{name}\"")
    };
    writeln!(
        w,
        "<DataArray type=\"{ty}\"{name} NumberOfComponents=\"{comps}\" format=\"binary\">{}</DataArray>",
        base64::engine::general_purpose::STANDARD.encode(raw)
    )
}

/// VTK XML PolyData, binary (base64 inline; see the module doc for the
/// arrays).
pub fn write_vtp(
    w: &mut impl Write,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    note: &str,
) -> io::Result<()> {
    let nv: usize = contours.iter().map(|c| c.borrow().positions.len()).sum();
    let nf: usize = contours.iter().map(|c| c.borrow().num_triangles()).sum();
    let escape = |s: &str| -> String {
        s.chars()
            .filter(|c| !c.is_control())
            .map(|c| match c {
                '<' | '>' | '&' | '"' => '_',
                c => c,
            })
            .collect()
    };
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "<PolyData>")?;
    // Field data: the names as a string array (ASCII: each string's bytes
    // then a 0, as VTK writes vtkStringArray), and the note.
    let strings = |items: &[String]| -> String {
        items
            .iter()
            .flat_map(|s| escape(s).into_bytes().into_iter().chain([0u8]))
            .map(|b| b.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let all: Vec<String> = (0..contours.len())
        .map(|i| {
            names
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("contour_{i}"))
        })
        .collect();
    writeln!(w, "<FieldData>")?;
    writeln!(
        w,
        "<Array type=\"String\" Name=\"contour_names\" NumberOfTuples=\"{}\" format=\"ascii\">{}</Array>",
        all.len(),
        strings(&all)
    )?;
    writeln!(
        w,
        "<Array type=\"String\" Name=\"note\" NumberOfTuples=\"1\" format=\"ascii\">{}</Array>",
        strings(&[note.to_owned()])
    )?;
    let numbers = |name: &str, ty: &str, items: Vec<String>| {
        format!(
            "<Array type=\"{ty}\" Name=\"{name}\" NumberOfTuples=\"{}\" format=\"ascii\">{}</Array>",
            items.len(),
            items.join(" ")
        )
    };
    let meshes = || contours.iter().map(|c| c.borrow());
    writeln!(
        w,
        "{}",
        numbers(
            "contour_arc",
            "Int32",
            meshes().map(|c| c.arc.0.to_string()).collect()
        )
    )?;
    writeln!(
        w,
        "{}",
        numbers(
            "contour_isovalue",
            "Float64",
            meshes().map(|c| format!("{:e}", c.isovalue)).collect()
        )
    )?;
    writeln!(w, "</FieldData>")?;
    writeln!(
        w,
        "<Piece NumberOfPoints=\"{nv}\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"{nf}\">"
    )?;
    let (mut points, mut normals, mut values) = (Vec::new(), Vec::new(), Vec::new());
    let (mut connectivity, mut offsets) = (Vec::new(), Vec::new());
    let (mut ids, mut arcs) = (Vec::new(), Vec::new());
    let mut base = 0i64;
    for (i, c) in contours.iter().enumerate() {
        let c = c.borrow();
        for (p, n) in c.positions.iter().zip(&c.normals) {
            p.iter()
                .for_each(|x| points.extend_from_slice(&x.to_le_bytes()));
            n.iter()
                .for_each(|x| normals.extend_from_slice(&x.to_le_bytes()));
            values.extend_from_slice(&c.isovalue.to_le_bytes());
        }
        for t in c.indices.chunks_exact(3) {
            for &v in t {
                connectivity.extend_from_slice(&(base + i64::from(v)).to_le_bytes());
            }
            offsets.extend_from_slice(&((connectivity.len() / 8) as i64).to_le_bytes());
            ids.extend_from_slice(&(i as i32).to_le_bytes());
            arcs.extend_from_slice(&(c.arc.0 as i32).to_le_bytes());
        }
        base += c.positions.len() as i64;
    }
    writeln!(w, "<PointData Normals=\"Normals\" Scalars=\"value\">")?;
    vtk_array(w, "Float32", "Normals", 3, &normals)?;
    vtk_array(w, "Float64", "value", 1, &values)?;
    writeln!(w, "</PointData>")?;
    writeln!(w, "<CellData Scalars=\"contour\">")?;
    vtk_array(w, "Int32", "contour", 1, &ids)?;
    vtk_array(w, "Int32", "arc", 1, &arcs)?;
    writeln!(w, "</CellData>")?;
    writeln!(w, "<Points>")?;
    vtk_array(w, "Float32", "Points", 3, &points)?;
    writeln!(w, "</Points>")?;
    writeln!(w, "<Polys>")?;
    vtk_array(w, "Int64", "connectivity", 1, &connectivity)?;
    vtk_array(w, "Int64", "offsets", 1, &offsets)?;
    writeln!(w, "</Polys>")?;
    writeln!(w, "</Piece>")?;
    writeln!(w, "</PolyData>")?;
    writeln!(w, "</VTKFile>")
}

/// Distinct colours (sRGB bytes), one per contour in turn.
const COLOURS: [[u8; 3]; 8] = [
    [227, 115, 51],
    [77, 153, 217],
    [115, 191, 89],
    [217, 89, 140],
    [230, 191, 64],
    [140, 115, 204],
    [89, 191, 191],
    [191, 140, 102],
];

/// Binary PLY (see the module doc): vertices with normal, colour and
/// contour index; triangles.
pub fn write_ply(
    w: &mut impl Write,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    note: &str,
) -> io::Result<()> {
    write_ply_coloured(w, contours, names, &[], note)
}

/// [`write_ply`] with contour `i` in `colours[i]` (sRGB; contours past
/// the end take the default colours).
pub fn write_ply_coloured(
    w: &mut impl Write,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    colours: &[[u8; 3]],
    note: &str,
) -> io::Result<()> {
    let nv: usize = contours.iter().map(|c| c.borrow().positions.len()).sum();
    let nf: usize = contours.iter().map(|c| c.borrow().num_triangles()).sum();
    let mut comments = String::new();
    if !note.is_empty() {
        comments += &format!("comment {note}\n");
    }
    for (i, c) in contours.iter().enumerate() {
        let name = names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("contour_{i}"));
        let name: String = name.chars().filter(|c| !c.is_control()).collect();
        let c = c.borrow();
        comments += &format!(
            "comment contour {i} {name} superarc {} isovalue {}\n",
            c.arc.0, c.isovalue
        );
    }
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment flexiso contours\n{comments}\
         element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nproperty int contour\n\
         element face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
    )?;
    for (i, c) in contours.iter().enumerate() {
        let c = c.borrow();
        let colour = colours
            .get(i)
            .copied()
            .unwrap_or(COLOURS[i % COLOURS.len()]);
        for (p, n) in c.positions.iter().zip(&c.normals) {
            for x in p.iter().chain(n) {
                w.write_all(&x.to_le_bytes())?;
            }
            w.write_all(&colour)?;
            w.write_all(&(i as i32).to_le_bytes())?;
        }
    }
    let mut base = 0u32;
    for c in contours {
        let c = c.borrow();
        for t in c.indices.chunks_exact(3) {
            w.write_all(&[3u8])?;
            for &v in t {
                w.write_all(&((base + v) as i32).to_le_bytes())?;
            }
        }
        base += c.positions.len() as u32;
    }
    Ok(())
}

/// OBJ: one object per contour, positions, normals, 1-based faces.
pub fn write_obj(
    w: &mut impl Write,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    note: &str,
) -> io::Result<()> {
    write_obj_with_materials(w, contours, names, None, note)
}

/// [`write_obj`] that names a material library (`mtllib`) and gives
/// each object the material of its name (`usemtl`), as
/// [`write_mtl`] writes them.
pub fn write_obj_with_materials(
    w: &mut impl Write,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    mtllib: Option<&str>,
    note: &str,
) -> io::Result<()> {
    writeln!(w, "# flexiso contours")?;
    if !note.is_empty() {
        writeln!(w, "# {note}")?;
    }
    if let Some(lib) = mtllib {
        writeln!(w, "mtllib {lib}")?;
    }
    let mut base = 1usize;
    for (i, c) in contours.iter().enumerate() {
        let c = c.borrow();
        let name = names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("contour_{i}"));
        writeln!(w, "o {name}")?;
        if mtllib.is_some() {
            writeln!(w, "usemtl {}", material_name(&name))?;
        }
        for p in &c.positions {
            writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
        }
        for n in &c.normals {
            writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
        }
        for t in c.indices.chunks_exact(3) {
            let [a, b, d] = [0, 1, 2].map(|k| t[k] as usize + base);
            writeln!(w, "f {a}//{a} {b}//{b} {d}//{d}")?;
        }
        base += c.positions.len();
    }
    Ok(())
}

/// Binary STL: every triangle of every contour with its facet normal.
pub fn write_stl(
    w: &mut impl Write,
    contours: &[impl Borrow<ContourMesh>],
    note: &str,
) -> io::Result<()> {
    let mut header = [0u8; 80];
    // "solid" must not start a binary STL's header (readers take it for
    // ASCII): ours starts with "flexiso".
    let text = format!("flexiso contours {note}");
    let text = &text.as_bytes()[..text.len().min(80)];
    header[..text.len()].copy_from_slice(text);
    w.write_all(&header)?;
    let nf: usize = contours.iter().map(|c| c.borrow().num_triangles()).sum();
    w.write_all(&(nf as u32).to_le_bytes())?;
    for c in contours {
        let c = c.borrow();
        for t in c.indices.chunks_exact(3) {
            let p = [0, 1, 2].map(|k| c.positions[t[k] as usize]);
            let u = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
            let v = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
            let mut n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if l > 0.0 {
                n = n.map(|x| x / l);
            }
            for x in n.iter().chain(p.iter().flatten()) {
                w.write_all(&x.to_le_bytes())?;
            }
            w.write_all(&[0, 0])?;
        }
    }
    Ok(())
}

/// The material name of an object: its name without whitespace (MTL
/// names are one word).
fn material_name(name: &str) -> String {
    name.split_whitespace().collect::<Vec<_>>().join("_")
}

/// A Wavefront material library: one diffuse (`Kd`) material per
/// contour, named as [`write_obj_with_materials`] uses them.
pub fn write_mtl(w: &mut impl Write, names: &[String], colours: &[[u8; 3]]) -> io::Result<()> {
    writeln!(w, "# flexiso contour colours")?;
    for (i, name) in names.iter().enumerate() {
        let [r, g, b] = colours
            .get(i)
            .copied()
            .unwrap_or(COLOURS[i % COLOURS.len()])
            .map(|c| f32::from(c) / 255.0);
        writeln!(
            w,
            "newmtl {}\nKa 0 0 0\nKd {r:.4} {g:.4} {b:.4}\nKs 0.1 0.1 0.1\nNs 20\nd 1\nillum 2\n",
            material_name(name)
        )?;
    }
    Ok(())
}

/// [`write_contours_noting`] keeping each contour's colour: PLY vertices
/// carry `colours[i]`; OBJ names a material library written beside it
/// (the same stem, `.mtl`), one material per contour. Other formats carry
/// no colour and are written as by [`write_contours_noting`]. Returns the
/// files written.
pub fn write_contours_coloured(
    path: &Path,
    contours: &[impl Borrow<ContourMesh>],
    names: &[String],
    colours: &[[u8; 3]],
    note: &str,
) -> Result<Vec<std::path::PathBuf>, ExportError> {
    let format = MeshFormat::from_path(path).ok_or_else(|| ExportError::UnknownFormat {
        path: path.display().to_string(),
    })?;
    let note: String = note.chars().filter(|c| !c.is_control()).collect();
    let write = |p: &Path, f: &dyn Fn(&mut dyn Write) -> io::Result<()>| {
        crate::output::write_whole(p, |w| f(w)).map_err(|error| ExportError::Io {
            path: p.display().to_string(),
            error,
        })
    };
    match format {
        MeshFormat::Ply => {
            write(path, &|mut w| {
                write_ply_coloured(&mut w, contours, names, colours, &note)
            })?;
            Ok(vec![path.to_path_buf()])
        }
        MeshFormat::Obj => {
            let mtl = path.with_extension("mtl");
            let lib = mtl
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "contours.mtl".into());
            write(&mtl, &|mut w| write_mtl(&mut w, names, colours))?;
            write(path, &|mut w| {
                write_obj_with_materials(&mut w, contours, names, Some(&lib), &note)
            })?;
            Ok(vec![path.to_path_buf(), mtl])
        }
        _ => {
            write_contours_as(path, format, contours, names, &note)?;
            Ok(vec![path.to_path_buf()])
        }
    }
}

#[cfg(test)]
mod coloured_tests {
    use super::*;

    fn triangle() -> ContourMesh {
        ContourMesh {
            arc: crate::tree::ArcId(0),
            isovalue: 1.0,
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: vec![[0.0, 0.0, 1.0]; 3],
            indices: vec![0, 1, 2],
            touches_boundary: true,
            ccw_outward: None,
            bounds: None,
            bands: Vec::new(),
        }
    }

    #[test]
    fn obj_names_its_materials_and_the_mtl_holds_each_colour() {
        let dir = tempfile::tempdir().expect("a temp dir");
        let path = dir.path().join("two.obj");
        let names = vec!["brain".to_string(), "left eye".to_string()];
        let written = write_contours_coloured(
            &path,
            &[triangle(), triangle()],
            &names,
            &[[255, 0, 0], [0, 128, 255]],
            "",
        )
        .expect("written");
        assert_eq!(written.len(), 2);
        let obj = std::fs::read_to_string(&path).expect("obj");
        assert!(obj.contains("mtllib two.mtl"));
        assert!(obj.contains("usemtl brain") && obj.contains("usemtl left_eye"));
        let mtl = std::fs::read_to_string(dir.path().join("two.mtl")).expect("mtl");
        assert!(mtl.contains("newmtl brain\nKa 0 0 0\nKd 1.0000 0.0000 0.0000"));
        assert!(mtl.contains("newmtl left_eye\nKa 0 0 0\nKd 0.0000 0.5020 1.0000"));
    }

    #[test]
    fn ply_vertices_carry_the_colours_given() {
        let mut out = Vec::new();
        write_ply_coloured(&mut out, &[triangle()], &[], &[[1, 2, 3]], "").expect("written");
        let body = &out[out
            .windows(11)
            .position(|w| w == b"end_header\n")
            .expect("header")
            + 11..];
        // x y z nx ny nz (24 bytes), then red green blue.
        assert_eq!(&body[24..27], &[1, 2, 3]);
    }
}
