//! A small software renderer for pictures of a scene (README, reports): z-buffered,
//! Lambert-shaded triangles, one view, no dependencies beyond PNG encoding.
//! An edge module (writes files).

use std::path::Path;

use crate::geometry::{SurfaceMesh, Vector3, VertexRegion};

/// Render meshes to a PNG of `width` x `height` pixels. The camera looks along
/// `view_dir` (world, towards the scene) with `up` up, framing all vertices.
pub fn render_png(
    meshes: &[&SurfaceMesh],
    path: &Path,
    width: u32,
    height: u32,
    view_dir: Vector3,
    up: Vector3,
) -> anyhow::Result<()> {
    let forward = view_dir.normalize();
    let right = forward.cross(&up).normalize();
    let up = right.cross(&forward);
    let project = |p: &Vector3| (p.dot(&right), p.dot(&up), p.dot(&forward));
    // frame all vertices with a margin
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for m in meshes {
        for v in &m.vertices {
            let (x, y, _) = project(&v.coords);
            lo = [lo[0].min(x), lo[1].min(y)];
            hi = [hi[0].max(x), hi[1].max(y)];
        }
    }
    let span = ((hi[0] - lo[0]) / width as f64)
        .max((hi[1] - lo[1]) / height as f64)
        .max(1e-9)
        * 1.1;
    let center = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let to_px = |x: f64, y: f64| {
        (
            (x - center[0]) / span + width as f64 / 2.0,
            height as f64 / 2.0 - (y - center[1]) / span,
        )
    };
    let mut depth = vec![f64::INFINITY; (width * height) as usize];
    let mut rgb = vec![255u8; (width * height * 3) as usize];
    let light = (-forward + up * 0.6 + right * 0.3).normalize();
    for m in meshes {
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.vertices[i as usize].coords);
            let n = (b - a).cross(&(c - a));
            if n.norm() == 0.0 || !n.iter().all(|x| x.is_finite()) {
                continue;
            }
            let shade = 0.35 + 0.65 * n.normalize().dot(&light).abs();
            let region = t
                .iter()
                .map(|&i| {
                    m.regions
                        .get(i as usize)
                        .copied()
                        .unwrap_or(VertexRegion::Flat)
                })
                .fold(VertexRegion::Flat, |acc, r| match (acc, r) {
                    (VertexRegion::Singular, _) | (_, VertexRegion::Singular) => {
                        VertexRegion::Singular
                    }
                    (VertexRegion::Curved, _) | (_, VertexRegion::Curved) => VertexRegion::Curved,
                    _ => VertexRegion::Flat,
                });
            let base = match region {
                VertexRegion::Flat => [90.0, 140.0, 220.0],
                VertexRegion::Curved => [235.0, 160.0, 60.0],
                VertexRegion::Singular => [220.0, 40.0, 40.0],
            };
            let color = base.map(|v| (v * shade).clamp(0.0, 255.0) as u8);
            let pts = [a, b, c].map(|p| {
                let (x, y, z) = project(&p);
                let (px, py) = to_px(x, y);
                (px, py, z)
            });
            fill_triangle(&pts, color, width, height, &mut depth, &mut rgb);
        }
    }
    let file =
        std::fs::File::create(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(&rgb)?;
    Ok(())
}

fn fill_triangle(
    p: &[(f64, f64, f64); 3],
    color: [u8; 3],
    width: u32,
    height: u32,
    depth: &mut [f64],
    rgb: &mut [u8],
) {
    let min_x = p
        .iter()
        .map(|q| q.0)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as i64;
    let max_x = p
        .iter()
        .map(|q| q.0)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(width as f64 - 1.0) as i64;
    let min_y = p
        .iter()
        .map(|q| q.1)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as i64;
    let max_y = p
        .iter()
        .map(|q| q.1)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(height as f64 - 1.0) as i64;
    let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
    if area.abs() < 1e-12 {
        return;
    }
    for y in min_y..=max_y {
        for x in min_x..=max_x {
            let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
            let w0 = ((p[1].0 - fx) * (p[2].1 - fy) - (p[2].0 - fx) * (p[1].1 - fy)) / area;
            let w1 = ((p[2].0 - fx) * (p[0].1 - fy) - (p[0].0 - fx) * (p[2].1 - fy)) / area;
            let w2 = 1.0 - w0 - w1;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * p[0].2 + w1 * p[1].2 + w2 * p[2].2;
            let i = (y as u32 * width + x as u32) as usize;
            if z < depth[i] {
                depth[i] = z;
                rgb[3 * i..3 * i + 3].copy_from_slice(&color);
            }
        }
    }
}
