//! Triangle meshes for mesh colliders: Wavefront OBJ (`v` and `f` records; polygons
//! are fanned into triangles) and STL (ASCII or binary; coincident vertices are
//! merged so neighbouring triangles share edges).

use std::path::Path;

use crate::geometry::Point3;

/// Vertices (file units) and triangles of the mesh at `path`, chosen by extension
/// (`.obj`, `.stl`). The error message names the file and the line or record.
pub fn load_mesh(path: &Path) -> Result<(Vec<Point3>, Vec<[u32; 3]>), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let result = match ext.as_str() {
        "obj" => parse_obj(&String::from_utf8_lossy(&bytes)),
        "stl" => parse_stl(&bytes),
        _ => Err("unknown mesh format (expected .obj or .stl)".to_string()),
    };
    let (vertices, triangles) = result.map_err(|m| format!("{}: {m}", path.display()))?;
    if let Some(bad) = vertices
        .iter()
        .position(|p| !p.coords.iter().all(|x| x.is_finite()))
    {
        return Err(format!("{}: vertex {bad} is not finite", path.display()));
    }
    Ok((vertices, triangles))
}

/// Parse OBJ text: `v x y z` and `f a b c ...` (1-based or negative indices, `a/t/n`
/// forms accepted); everything else is ignored.
fn parse_obj(text: &str) -> Result<(Vec<Point3>, Vec<[u32; 3]>), String> {
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let line_no = ln + 1;
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let mut c = [0.0; 3];
                for x in &mut c {
                    *x = it
                        .next()
                        .and_then(|s| s.parse::<f64>().ok())
                        .ok_or_else(|| format!("line {line_no}: expected `v x y z`"))?;
                }
                vertices.push(Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let mut idx = Vec::new();
                for tok in it {
                    let first = tok.split('/').next().unwrap_or("");
                    let i: i64 = first
                        .parse()
                        .map_err(|_| format!("line {line_no}: bad face index `{tok}`"))?;
                    let n = vertices.len() as i64;
                    let v = if i > 0 { i - 1 } else { n + i };
                    if i == 0 || v < 0 || v >= n {
                        return Err(format!(
                            "line {line_no}: face index {i} out of range (1..={n})"
                        ));
                    }
                    idx.push(v as u32);
                }
                if idx.len() < 3 {
                    return Err(format!("line {line_no}: a face needs 3 vertices"));
                }
                for k in 1..idx.len() - 1 {
                    triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok((vertices, triangles))
}

/// Parse STL, binary when its size matches the triangle count of the header, else
/// ASCII.
fn parse_stl(bytes: &[u8]) -> Result<(Vec<Point3>, Vec<[u32; 3]>), String> {
    let mut soup: Vec<[f64; 3]> = Vec::new();
    let binary = bytes.len() >= 84 && {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        bytes.len() == 84 + 50 * count
    };
    if binary {
        let count = (bytes.len() - 84) / 50;
        for t in 0..count {
            let rec = &bytes[84 + 50 * t..84 + 50 * (t + 1)];
            for v in 0..3 {
                let mut p = [0.0; 3];
                for (c, x) in p.iter_mut().enumerate() {
                    let o = 12 + 12 * v + 4 * c;
                    *x = f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]) as f64;
                }
                soup.push(p);
            }
        }
    } else {
        let text = String::from_utf8_lossy(bytes);
        if !text.trim_start().starts_with("solid") {
            return Err("neither binary STL (size mismatch) nor ASCII STL (`solid ...`)".into());
        }
        for (ln, line) in text.lines().enumerate() {
            let mut it = line.split_whitespace();
            if it.next() == Some("vertex") {
                let mut p = [0.0; 3];
                for x in &mut p {
                    *x = it
                        .next()
                        .and_then(|s| s.parse::<f64>().ok())
                        .ok_or_else(|| format!("line {}: expected `vertex x y z`", ln + 1))?;
                }
                soup.push(p);
            }
        }
        if !soup.len().is_multiple_of(3) {
            return Err(format!(
                "{} vertices is not a whole number of facets",
                soup.len()
            ));
        }
    }
    // merge coincident vertices (exact bit patterns; sorted, so deterministic)
    let mut order: Vec<usize> = (0..soup.len()).collect();
    let key = |p: &[f64; 3]| p.map(|x| (x + 0.0).to_bits());
    order.sort_by_key(|&i| (key(&soup[i]), i));
    let mut index = vec![0u32; soup.len()];
    let mut vertices = Vec::new();
    let mut last = None;
    for &i in &order {
        let k = key(&soup[i]);
        if last != Some(k) {
            vertices.push(Point3::new(soup[i][0], soup[i][1], soup[i][2]));
            last = Some(k);
        }
        index[i] = (vertices.len() - 1) as u32;
    }
    let triangles = index
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    Ok((vertices, triangles))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_quads_are_fanned_and_indices_checked() {
        let (v, t) = parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 -1\n").unwrap();
        assert_eq!(v.len(), 4);
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(parse_obj("v 0 0 0\nf 1 2 3\n")
            .unwrap_err()
            .contains("line 2"));
    }

    #[test]
    fn stl_ascii_and_binary_share_vertices() {
        let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let (v, t) = parse_stl(ascii.as_bytes()).unwrap();
        assert_eq!(v.len(), 4);
        assert_eq!(t.len(), 2);
        let mut bin = vec![0u8; 80];
        bin.extend_from_slice(&2u32.to_le_bytes());
        for tri in [
            [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        ] {
            bin.extend_from_slice(&[0u8; 12]);
            for p in tri {
                for x in p {
                    bin.extend_from_slice(&x.to_le_bytes());
                }
            }
            bin.extend_from_slice(&[0u8; 2]);
        }
        let (vb, tb) = parse_stl(&bin).unwrap();
        assert_eq!(vb.len(), 4);
        assert_eq!(tb.len(), 2);
        // a binary file cut short is neither binary (size) nor ASCII (`solid`)
        let cut = &bin[..bin.len() - 7];
        assert!(parse_stl(cut).unwrap_err().contains("neither binary STL"));
        // an ASCII file whose facets are cut short
        let short = "solid t\nvertex 0 0 0\nvertex 1 0 0\nendsolid t\n";
        assert!(parse_stl(short.as_bytes())
            .unwrap_err()
            .contains("not a whole number of facets"));
    }

    #[test]
    fn bad_files_are_errors_that_name_them() {
        let dir = std::env::temp_dir().join(format!("mesh_file_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let nan = dir.join("nan.obj");
        std::fs::write(&nan, "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let e = load_mesh(&nan).unwrap_err();
        assert!(
            e.contains("nan.obj") && e.contains("vertex 0 is not finite"),
            "{e}"
        );
        let e = load_mesh(&dir.join("absent.stl")).unwrap_err();
        assert!(e.contains("cannot read") && e.contains("absent.stl"), "{e}");
        let dae = dir.join("x.dae");
        std::fs::write(&dae, "<COLLADA/>").unwrap();
        assert!(load_mesh(&dae).unwrap_err().contains("unknown mesh format"));
    }
}
