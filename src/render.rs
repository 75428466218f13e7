//! Pictures of a scene (README, reports): a small software renderer that makes the
//! surface's shape readable. A perspective camera framing every vertex, a z-buffer and
//! 2x2 supersampling; Lambert shading from a light fixed to the camera (upper left),
//! the two sides of the surface in different tints (the material +z side in its
//! region colour, the other side pale), a depth cue (far parts fade toward the
//! background); ruling and crease lines and the boundary drawn over the surface where
//! visible, singular points as red dots; when the camera looks down, a floor under the
//! scene with the surface's shadow. `render` is pure (meshes in, pixels out); only
//! `write_png` touches a file.

use std::path::{Path, PathBuf};

use crate::camera::tint::{self, mix, BACKGROUND, FLOOR};
use crate::camera::{world_colliders, Frame, Renderer, Snapshot};
use crate::geometry::{SurfaceMesh, Vector3, VertexRegion};
use crate::scene::{CameraMount, Scene};

/// What can go wrong making a picture.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("--size must be WIDTHxHEIGHT with both in 16..=8192, got `{0}`")]
    Size(String),
    #[error("--view takes three finite numbers x,y,z, not all zero")]
    View,
    #[error("nothing to render: the scene has no finite triangle")]
    Empty,
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: PNG: {source}")]
    Png {
        path: PathBuf,
        source: png::EncodingError,
    },
    #[error("the scene has no camera `{name}` (its cameras: {known})")]
    NoCamera { name: String, known: String },
    #[error("camera `{name}` follows the TF frame `{frame}`: a picture needs a camera with position and look_at")]
    TfCamera { name: String, frame: String },
}

/// Camera and picture size.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// Picture size, pixels.
    pub width: u32,
    pub height: u32,
    /// Viewing direction (world, from the camera towards the scene); any length.
    pub view_dir: Vector3,
}

/// An 8-bit RGB picture, rows from the top.
#[derive(Debug, Clone)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

impl Image {
    /// The colour of pixel (x, y) (the tests read the picture through it).
    #[cfg(test)]
    fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y * self.width + x) as usize;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
}

/// Parse `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> Result<(u32, u32), RenderError> {
    let parsed = s
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if (16..=8192).contains(&w) && (16..=8192).contains(&h) => Ok((w, h)),
        _ => Err(RenderError::Size(s.to_string())),
    }
}

/// Supersampling factor per axis (2: four samples a pixel, averaged).
const SS: u32 = 2;
/// Vertical field of view, rad: mild perspective (a 35 mm lens is ~0.7).
const FOV: f64 = 0.55;
/// Largest fraction of the background mixed into the farthest point (depth cue).
const FOG: f64 = 0.35;
/// Share of the floor's brightness left in the shadow.
const SHADOW: f64 = 0.78;
const LINE: [f64; 3] = [35.0, 38.0, 48.0];
const SINGULAR: [f64; 3] = [215.0, 30.0, 30.0];
/// Adjacent triangles whose normals differ by more than this are a crease, rad.
const CREASE_ANGLE: f64 = 0.35;

/// Render `meshes` as seen along `opts.view_dir`.
pub fn render(meshes: &[&SurfaceMesh], opts: &RenderOptions) -> Result<Image, RenderError> {
    let view = opts.view_dir;
    if !view.iter().all(|v| v.is_finite()) || view.norm() == 0.0 {
        return Err(RenderError::View);
    }
    let cam = Camera::framing(meshes, view, opts.width * SS, opts.height * SS)
        .ok_or(RenderError::Empty)?;
    let mut r = Raster::new(opts.width * SS, opts.height * SS);
    if cam.forward.z < -0.05 {
        draw_floor(&mut r, &cam, meshes);
    }
    for m in meshes {
        draw_surface(&mut r, &cam, m);
    }
    for m in meshes {
        draw_lines(&mut r, &cam, m);
        draw_singular_points(&mut r, &cam, m);
    }
    r.fog(cam.depth_range, cam.radius);
    Ok(r.downsample())
}

/// Render and write a PNG.
pub fn render_png(
    meshes: &[&SurfaceMesh],
    path: &Path,
    opts: &RenderOptions,
) -> Result<(), RenderError> {
    let image = render(meshes, opts)?;
    write_png(&image, path)
}

/// Write `image` as an 8-bit RGB PNG.
pub fn write_png(image: &Image, path: &Path) -> Result<(), RenderError> {
    let file = std::fs::File::create(path).map_err(|source| RenderError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let png_err = |source| RenderError::Png {
        path: path.to_path_buf(),
        source,
    };
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), image.width, image.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(png_err)?;
    writer.write_image_data(&image.rgb).map_err(png_err)?;
    writer.finish().map_err(png_err)
}

/// A perspective camera: eye, orthonormal frame, and the screen mapping that frames
/// every finite vertex with a margin.
struct Camera {
    eye: Vector3,
    right: Vector3,
    up: Vector3,
    forward: Vector3,
    /// Screen pixels per unit of x/z (and y/z), and the screen centre's offset.
    scale: f64,
    offset: [f64; 2],
    /// Camera depth of the nearest and farthest vertex, m.
    depth_range: [f64; 2],
    /// Scene radius, m (line and point depth bias scale with it).
    radius: f64,
}

impl Camera {
    fn framing(meshes: &[&SurfaceMesh], view: Vector3, w: u32, h: u32) -> Option<Camera> {
        let points: Vec<Vector3> = meshes
            .iter()
            .flat_map(|m| m.vertices.iter().map(|p| p.coords))
            .filter(|p| p.iter().all(|x| x.is_finite()))
            .collect();
        let first = *points.first()?;
        let (lo, hi) = points
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
        let center = (lo + hi) / 2.0;
        let radius = ((hi - lo).norm() / 2.0).max(1e-6);
        let forward = view.normalize();
        // z is up in every scene; looking straight down, y is
        let world_up = if forward.z.abs() > 0.99 {
            Vector3::y()
        } else {
            Vector3::z()
        };
        let right = forward.cross(&world_up).normalize();
        let up = right.cross(&forward);
        let eye = center - forward * (1.15 * radius / (FOV / 2.0).sin());
        let mut cam = Camera {
            eye,
            right,
            up,
            forward,
            scale: 1.0,
            offset: [0.0; 2],
            depth_range: [f64::INFINITY, f64::NEG_INFINITY],
            radius,
        };
        let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &points {
            let (x, y, z) = cam.project(p);
            a = [a[0].min(x), a[1].min(y)];
            b = [b[0].max(x), b[1].max(y)];
            cam.depth_range = [cam.depth_range[0].min(z), cam.depth_range[1].max(z)];
        }
        // fit the projected box into 90 % of the picture, centred
        let scale = (0.9 * w as f64 / (b[0] - a[0]).max(1e-9))
            .min(0.9 * h as f64 / (b[1] - a[1]).max(1e-9));
        cam.scale = scale;
        cam.offset = [
            w as f64 / 2.0 - scale * (a[0] + b[0]) / 2.0,
            h as f64 / 2.0 + scale * (a[1] + b[1]) / 2.0,
        ];
        Some(cam)
    }

    /// Perspective coordinates (x/z, y/z, z) before the screen mapping.
    fn project(&self, p: &Vector3) -> (f64, f64, f64) {
        let d = p - self.eye;
        let z = d.dot(&self.forward).max(1e-9);
        (d.dot(&self.right) / z, d.dot(&self.up) / z, z)
    }

    /// Screen position (pixels, y down) and camera depth, m.
    fn to_screen(&self, p: &Vector3) -> [f64; 3] {
        let (x, y, z) = self.project(p);
        [
            self.offset[0] + self.scale * x,
            self.offset[1] - self.scale * y,
            z,
        ]
    }

    /// Unit direction towards the light: from the upper left, behind the camera.
    fn light(&self) -> Vector3 {
        (-self.forward + self.up * 0.9 - self.right * 0.5).normalize()
    }
}

fn triangle(m: &SurfaceMesh, t: &[u32; 3]) -> Option<[Vector3; 3]> {
    let p = t.map(|i| m.vertices[i as usize].coords);
    let ok = p.iter().all(|v| v.iter().all(|x| x.is_finite()));
    let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
    (ok && n.norm() > 0.0).then_some(p)
}

fn draw_surface(r: &mut Raster, cam: &Camera, m: &SurfaceMesh) {
    let light = cam.light();
    for t in &m.triangles {
        let Some(p) = triangle(m, t) else { continue };
        // material +z side normal (triangles are counter-clockwise seen from +z)
        let n = (p[1] - p[0]).cross(&(p[2] - p[0])).normalize();
        let front = n.dot(&cam.forward) < 0.0;
        let facing = if front { n } else { -n };
        let lambert = facing.dot(&light).max(0.0);
        let shade = tint::shade(lambert);
        // the material +z side in its region's colour, the other side pale (the tints
        // the camera uses too)
        let color = tint::surface(m, t, front).map(|c| c * shade);
        r.fill(&p.map(|q| cam.to_screen(&q)), color, 0.0);
    }
}

/// The floor: a square under the scene at 2 % of its size below its lowest point, and
/// the surface's shadow on it cast by a light nearly overhead.
fn draw_floor(r: &mut Raster, cam: &Camera, meshes: &[&SurfaceMesh]) {
    let z0 = meshes
        .iter()
        .flat_map(|m| m.vertices.iter().map(|p| p.z))
        .filter(|z| z.is_finite())
        .fold(f64::INFINITY, f64::min)
        - 0.02 * cam.radius;
    let c = cam.eye + cam.forward * (1.15 * cam.radius / (FOV / 2.0).sin());
    let s = 8.0 * cam.radius;
    let corner = |dx: f64, dy: f64| Vector3::new(c.x + dx * s, c.y + dy * s, z0);
    let quad = [
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(1.0, 1.0),
        corner(-1.0, 1.0),
    ];
    for tri in [[0, 1, 2], [0, 2, 3]] {
        r.fill(&tri.map(|i| cam.to_screen(&quad[i])), FLOOR, 0.0);
    }
    let sun = Vector3::new(0.25, 0.35, 1.0).normalize();
    let on_floor = |p: Vector3| p - sun * ((p.z - z0) / sun.z);
    let bias = 1e-3 * cam.radius;
    for m in meshes {
        for t in &m.triangles {
            let Some(p) = triangle(m, t) else { continue };
            let s = p.map(|q| cam.to_screen(&on_floor(q)));
            r.fill(&s, FLOOR.map(|c| c * SHADOW), bias);
        }
    }
}

/// Rulings, creases (adjacent triangles at an angle) and the boundary, each where no
/// surface hides it.
fn draw_lines(r: &mut Raster, cam: &Camera, m: &SurfaceMesh) {
    let bias = 0.01 * cam.radius;
    let thin = SS as f64 * 0.7;
    let thick = SS as f64 * 1.1;
    for [a, b] in &m.rulings {
        r.line(cam, m, [*a, *b], LINE, 0.55, thin, bias);
    }
    // each undirected edge with its triangles' normals
    let mut edges: Vec<([u32; 2], Vector3)> = Vec::with_capacity(3 * m.triangles.len());
    for t in &m.triangles {
        let Some(p) = triangle(m, t) else { continue };
        let n = (p[1] - p[0]).cross(&(p[2] - p[0])).normalize();
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            edges.push(([a.min(b), a.max(b)], n));
        }
    }
    edges.sort_unstable_by_key(|e| e.0);
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j].0 == edges[i].0 {
            j += 1;
        }
        if j - i == 1 {
            r.line(cam, m, edges[i].0, LINE, 0.85, thick, bias);
        } else if edges[i].1.angle(&edges[i + 1].1) > CREASE_ANGLE {
            r.line(cam, m, edges[i].0, LINE, 0.7, thin, bias);
        }
        i = j;
    }
}

fn draw_singular_points(r: &mut Raster, cam: &Camera, m: &SurfaceMesh) {
    let bias = 0.02 * cam.radius;
    for (p, region) in m.vertices.iter().zip(&m.regions) {
        if *region == VertexRegion::Singular && p.coords.iter().all(|x| x.is_finite()) {
            let s = cam.to_screen(&p.coords);
            r.disc(s, SS as f64 * 3.2, LINE, bias);
            r.disc(s, SS as f64 * 2.3, SINGULAR, bias);
        }
    }
}

/// The supersampled picture being drawn: colours and camera depths.
struct Raster {
    w: u32,
    h: u32,
    depth: Vec<f64>,
    rgb: Vec<[f64; 3]>,
}

impl Raster {
    fn new(w: u32, h: u32) -> Raster {
        // a vertical gradient: slightly darker at the bottom
        let rgb = (0..h)
            .flat_map(|y| {
                let t = y as f64 / h as f64;
                std::iter::repeat_n(mix(BACKGROUND, [226.0, 230.0, 238.0], t), w as usize)
            })
            .collect();
        Raster {
            w,
            h,
            depth: vec![f64::INFINITY; (w * h) as usize],
            rgb,
        }
    }

    /// Fill a screen triangle (x, y in pixels, z camera depth) where it is nearer than
    /// what is drawn + `bias` (m); `bias` > 0 draws onto a coplanar surface without
    /// changing its depth.
    fn fill(&mut self, p: &[[f64; 3]; 3], color: [f64; 3], bias: f64) {
        let area =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
        if !area.is_finite() || area.abs() < 1e-12 {
            return;
        }
        let lo = |k: usize| p.iter().map(|q| q[k]).fold(f64::INFINITY, f64::min);
        let hi = |k: usize| p.iter().map(|q| q[k]).fold(f64::NEG_INFINITY, f64::max);
        let x0 = lo(0).floor().max(0.0) as u32;
        let x1 = hi(0).ceil().min(self.w as f64 - 1.0);
        let y0 = lo(1).floor().max(0.0) as u32;
        let y1 = hi(1).ceil().min(self.h as f64 - 1.0);
        if x1 < 0.0 || y1 < 0.0 {
            return;
        }
        // 1/z is affine in screen space: interpolate it, not z
        let inv = p.map(|q| 1.0 / q[2]);
        for y in y0..=y1 as u32 {
            for x in x0..=x1 as u32 {
                let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
                let edge = |a: &[f64; 3], b: &[f64; 3]| {
                    ((a[0] - fx) * (b[1] - fy) - (b[0] - fx) * (a[1] - fy)) / area
                };
                let w0 = edge(&p[1], &p[2]);
                let w1 = edge(&p[2], &p[0]);
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = 1.0 / (w0 * inv[0] + w1 * inv[1] + w2 * inv[2]);
                let i = (y * self.w + x) as usize;
                if bias > 0.0 {
                    if z <= self.depth[i] + bias && self.depth[i].is_finite() {
                        self.rgb[i] = color;
                    }
                } else if z < self.depth[i] {
                    self.depth[i] = z;
                    self.rgb[i] = color;
                }
            }
        }
    }

    /// A line between two mesh vertices, `width` pixels wide, blended with `alpha`
    /// where it is no more than `bias` (m) behind the surface.
    #[allow(clippy::too_many_arguments)]
    fn line(
        &mut self,
        cam: &Camera,
        m: &SurfaceMesh,
        [a, b]: [u32; 2],
        color: [f64; 3],
        alpha: f64,
        width: f64,
        bias: f64,
    ) {
        let (pa, pb) = (m.vertices[a as usize].coords, m.vertices[b as usize].coords);
        if !(pa.iter().chain(pb.iter()).all(|x| x.is_finite())) {
            return;
        }
        let (sa, sb) = (cam.to_screen(&pa), cam.to_screen(&pb));
        let len = ((sb[0] - sa[0]).powi(2) + (sb[1] - sa[1]).powi(2)).sqrt();
        let steps = (len * 2.0).ceil().clamp(1.0, 1e5) as usize;
        let half = width / 2.0;
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            let s = [0, 1, 2].map(|j| sa[j] + (sb[j] - sa[j]) * t);
            let (x0, x1) = ((s[0] - half).round(), (s[0] + half).round());
            let (y0, y1) = ((s[1] - half).round(), (s[1] + half).round());
            for y in y0 as i64..=y1 as i64 {
                for x in x0 as i64..=x1 as i64 {
                    self.blend(x, y, s[2], bias, color, alpha);
                }
            }
        }
    }

    /// A filled disc of `radius` pixels around a screen point.
    fn disc(&mut self, s: [f64; 3], radius: f64, color: [f64; 3], bias: f64) {
        let r = radius.ceil() as i64;
        for dy in -r..=r {
            for dx in -r..=r {
                if ((dx * dx + dy * dy) as f64) <= radius * radius {
                    let (x, y) = (s[0].round() as i64 + dx, s[1].round() as i64 + dy);
                    self.blend(x, y, s[2], bias, color, 1.0);
                }
            }
        }
    }

    fn blend(&mut self, x: i64, y: i64, z: f64, bias: f64, color: [f64; 3], alpha: f64) {
        if x < 0 || y < 0 || x >= self.w as i64 || y >= self.h as i64 {
            return;
        }
        let i = (y as u32 * self.w + x as u32) as usize;
        if z <= self.depth[i] + bias {
            self.rgb[i] = mix(self.rgb[i], color, alpha);
        }
    }

    /// Depth cue: mix the background into every drawn pixel by its depth.
    fn fog(&mut self, range: [f64; 2], radius: f64) {
        // relative to the scene's size, so a scene seen face-on is not all fog
        let span = (range[1] - range[0]).max(radius);
        for (c, z) in self.rgb.iter_mut().zip(&self.depth) {
            if z.is_finite() {
                let t = ((z - range[0]) / span).clamp(0.0, 1.0);
                *c = mix(*c, BACKGROUND, FOG * t);
            }
        }
    }

    /// Average each SS x SS block into one 8-bit pixel (antialiasing).
    fn downsample(&self) -> Image {
        let (w, h) = (self.w / SS, self.h / SS);
        let mut rgb = Vec::with_capacity((w * h * 3) as usize);
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0.0; 3];
                for sy in 0..SS {
                    for sx in 0..SS {
                        let c = self.rgb[((y * SS + sy) * self.w + x * SS + sx) as usize];
                        (0..3).for_each(|k| sum[k] += c[k]);
                    }
                }
                let n = (SS * SS) as f64;
                rgb.extend(sum.map(|s| (s / n).round().clamp(0.0, 255.0) as u8));
            }
        }
        Image {
            width: w,
            height: h,
            rgb,
        }
    }
}

/// The frame camera `name` of `scene` sees at the scene's current time: frame index
/// floor(t rate) for the noise, the scene's `seed`.
pub fn camera_frame(scene: &Scene, name: &str) -> Result<Frame, RenderError> {
    let Some(cam) = scene.cameras.iter().find(|c| c.name == name) else {
        let known: Vec<&str> = scene.cameras.iter().map(|c| c.name.as_str()).collect();
        return Err(RenderError::NoCamera {
            name: name.into(),
            known: if known.is_empty() {
                "none".into()
            } else {
                known.join(", ")
            },
        });
    };
    let pose = match &cam.mount {
        CameraMount::Fixed(pose) => *pose,
        CameraMount::TfFrame(frame) => {
            return Err(RenderError::TfCamera {
                name: name.into(),
                frame: frame.clone(),
            })
        }
    };
    let world = &scene.world;
    let mut snapshot = Snapshot::default();
    snapshot.capture(world);
    let mut renderer = Renderer::new(cam.camera, world_colliders(world));
    // a tick lands on t = k / rate: a nanosecond's slack for the rounding of t
    let index = (world.time() * cam.rate + 1e-9).floor().max(0.0) as u64;
    let key = cam.noise_key(scene.source.seed, index);
    Ok(renderer.render(&snapshot, &pose, &key).clone())
}

/// A camera frame's colour image.
pub fn color_image(frame: &Frame) -> Image {
    Image {
        width: frame.width,
        height: frame.height,
        rgb: frame.color.clone(),
    }
}

/// A camera frame's depth, colour-mapped (turbo: blue at the nearest depth of the
/// frame, red at the farthest; black where there is no depth), and that range, m (None:
/// no depth anywhere).
pub fn depth_image(frame: &Frame) -> (Image, Option<[f32; 2]>) {
    let depths = frame
        .depth
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let range = depths
        .clone()
        .filter(|d| d.is_finite())
        .fold(None::<[f32; 2]>, |r, d| match r {
            None => Some([d, d]),
            Some([lo, hi]) => Some([lo.min(d), hi.max(d)]),
        });
    let [lo, hi] = range.unwrap_or([0.0, 1.0]);
    let span = (hi - lo).max(1e-6);
    let rgb = depths
        .flat_map(|d| match d.is_finite() {
            true => turbo(((d - lo) / span) as f64),
            false => [0, 0, 0],
        })
        .collect();
    let image = Image {
        width: frame.width,
        height: frame.height,
        rgb,
    };
    (image, range)
}

/// Where `render --camera` writes the depth picture beside OUT.png: OUT_depth.png.
pub fn depth_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "camera".into());
    out.with_file_name(format!("{stem}_depth.png"))
}

/// Google's turbo colour map (Mikhailov 2019, the polynomial approximation) at x in
/// [0, 1].
fn turbo(x: f64) -> [u8; 3] {
    let x = x.clamp(0.0, 1.0);
    let p = [1.0, x, x * x, x * x * x, x.powi(4), x.powi(5)];
    let dot = |c: [f64; 6]| (0..6).map(|k| c[k] * p[k]).sum::<f64>();
    let r = dot([
        0.13572138,
        4.61539260,
        -42.66032258,
        132.13108234,
        -152.94239396,
        59.28637943,
    ]);
    let g = dot([
        0.09140261,
        2.19418839,
        4.84296658,
        -14.18503333,
        4.27729857,
        2.82956604,
    ]);
    let b = dot([
        0.10667330,
        12.64194608,
        -60.58204836,
        110.36276771,
        -89.90310912,
        27.34824973,
    ]);
    [r, g, b].map(|c| (255.0 * c).round().clamp(0.0, 255.0) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Point2, Point3};

    /// A unit square in z = `z` (two triangles, counter-clockwise seen from +z), all
    /// vertices in `region`, with the ruling `rulings`.
    fn square(z: f64, region: VertexRegion, rulings: Vec<[u32; 2]>) -> SurfaceMesh {
        let v = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        SurfaceMesh {
            vertices: v.iter().map(|p| Point3::new(p[0], p[1], z)).collect(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            material: v.iter().map(|p| Point2::new(p[0], p[1])).collect(),
            rulings,
            regions: vec![region; 4],
        }
    }

    fn opts(view: [f64; 3]) -> RenderOptions {
        RenderOptions {
            width: 64,
            height: 64,
            view_dir: Vector3::new(view[0], view[1], view[2]),
        }
    }

    /// The picture of `meshes` seen from straight above (y up on the screen).
    fn from_above(meshes: &[&SurfaceMesh]) -> Image {
        render(meshes, &opts([0.0, 0.0, -1.0])).unwrap()
    }

    fn brightness(c: [u8; 3]) -> u32 {
        c.iter().map(|&x| x as u32).sum()
    }

    #[test]
    fn the_two_sides_of_the_surface_have_different_tints() {
        let m = square(0.0, VertexRegion::Flat, vec![]);
        let top = from_above(&[&m]).pixel(20, 20);
        let bottom = render(&[&m], &opts([0.0, 0.0, 1.0])).unwrap().pixel(20, 20);
        // the material +z side in the flat colour (blue), the other side greyed
        let saturation = |c: [u8; 3]| c.iter().max().unwrap() - c.iter().min().unwrap();
        assert!(top[2] > top[0] + 60, "{top:?}");
        assert!(
            2 * saturation(bottom) < saturation(top),
            "{top:?} vs {bottom:?}"
        );
    }

    #[test]
    fn a_face_turned_to_the_light_is_brighter() {
        // a roof along x: the face towards +y (where the light is, seen from above
        // with y up on the screen) against the face towards -y
        let v = [
            [0.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 0.0, 0.4],
            [0.0, 0.0, 0.4],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let m = SurfaceMesh {
            vertices: v.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect(),
            triangles: vec![[0, 1, 2], [0, 2, 3], [3, 2, 4], [3, 4, 5]],
            material: v.iter().map(|p| Point2::new(p[0], p[1])).collect(),
            rulings: vec![],
            regions: vec![VertexRegion::Flat; 6],
        };
        let img = from_above(&[&m]);
        // screen rows run down: the +y face is the upper half
        let towards = brightness(img.pixel(32, 20));
        let away = brightness(img.pixel(32, 44));
        assert!(
            towards > away + 30,
            "towards the light {towards}, away {away}"
        );
    }

    #[test]
    fn rulings_are_drawn_where_visible_and_hidden_behind_a_surface() {
        let ruled = square(0.0, VertexRegion::Flat, vec![[0, 2]]);
        let img = from_above(&[&ruled]);
        // the diagonal (0,0)-(1,1) runs from the lower left to the upper right
        let on = brightness(img.pixel(32, 32));
        let off = brightness(img.pixel(20, 20));
        assert!(on + 120 < off, "on the ruling {on}, beside it {off}");
        // a bigger square above it hides the ruling: the centre is plain surface
        let mut cover = square(0.5, VertexRegion::Flat, vec![]);
        for p in &mut cover.vertices {
            p.x = 3.0 * p.x - 1.0;
            p.y = 3.0 * p.y - 1.0;
        }
        let img = from_above(&[&ruled, &cover]);
        let (c, near) = (img.pixel(32, 32), img.pixel(36, 32));
        assert!(
            brightness(c).abs_diff(brightness(near)) < 6,
            "{c:?} vs {near:?}"
        );
    }

    #[test]
    fn bent_parts_and_singular_points_have_their_colours() {
        let curved = square(0.0, VertexRegion::Curved, vec![]);
        let c = from_above(&[&curved]).pixel(20, 20);
        assert!(c[0] > c[2] + 60, "orange, got {c:?}");
        let mut m = square(0.0, VertexRegion::Flat, vec![]);
        m.regions[2] = VertexRegion::Singular;
        let img = from_above(&[&m]);
        // vertex 2 = (1, 1): the upper right corner of the framed square
        let corner = (0..64)
            .flat_map(|y| (0..64).map(move |x| (x, y)))
            .map(|(x, y)| img.pixel(x, y))
            .filter(|p| p[0] > 150 && p[1] < 90 && p[2] < 90)
            .count();
        assert!(corner > 4, "{corner} red pixels");
    }

    #[test]
    fn bad_sizes_and_views_are_refused() {
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        for bad in ["640", "640x", "x480", "0x480", "640x-1", "99999x10"] {
            assert!(
                matches!(parse_size(bad), Err(RenderError::Size(_))),
                "{bad}"
            );
        }
        let m = square(0.0, VertexRegion::Flat, vec![]);
        assert!(matches!(
            render(&[&m], &opts([0.0, 0.0, 0.0])),
            Err(RenderError::View)
        ));
        assert!(matches!(
            render(&[&m], &opts([f64::NAN, 0.0, 1.0])),
            Err(RenderError::View)
        ));
        let mut nan = m.clone();
        nan.vertices.iter_mut().for_each(|p| p.x = f64::NAN);
        assert!(matches!(
            render(&[&nan], &opts([0.0, 0.0, -1.0])),
            Err(RenderError::Empty)
        ));
    }
}
