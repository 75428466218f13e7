//! `Simulation.save()` bytes: the scene as loaded (its YAML text, its file name, the
//! overrides), the seed, and every command applied since t = 0 (each step's handle
//! targets, f64 bits as they were; grasps and releases as asked), with a fingerprint of the state reached. Loading
//! builds the scene again and replays the commands: the simulator is deterministic
//! (same scene, seed and inputs give bit-identical states), so the loaded simulation is
//! the saved one bit for bit, and the fingerprint checks that it is.
//!
//! Why a command log and not the state itself: the core keeps no serializable state (it
//! is pure, without serde, ARCHITECTURE.md) and each simulator holds much more than its
//! mesh (the ribbon's history X^n, V^n and adaptive penalty; the paper's two meshes,
//! regions, junctions and singular vertices; the contact stage's buffers); a dump of
//! all of it would have to follow every change of every simulator. The log needs
//! nothing from the core but determinism, which the project tests already
//! (`runs_are_bit_identical`). The cost: loading re-simulates the saved run.
//!
//! Layout (little-endian): magic `DSIMSAVE`, version u32, the YAML text, the file name
//! and each override as u32 length + UTF-8, the seed u64, the handle count u32, the
//! command count u64, the commands, then the fingerprint u64. Version 2 writes each
//! command as a kind byte and its fields:
//! - 0, a step: per handle a tag byte (0: scripted, 1: a pose of 7 f64: x, y, z, then
//!   the quaternion's i, j, k, w);
//! - 1, a grasp: handle u32, object u32, where (0: a material point, 2 f64 u, v;
//!   1: the nearest graspable point to 3 f64 x, y, z within an f64 max distance), the
//!   hold (0: the handle's own, 1: position, 2: normal and its stiffness f64, 3: full);
//! - 2, a release: handle u32.
//!
//! Version 1 (steps only, before grasps, never on main) is refused with a message.

use developable_sim::geometry::{Point2, Point3, Pose};
use developable_sim::sim::{GraspAt, Hold, World};
use nalgebra::{Quaternion, Translation3, UnitQuaternion};

const MAGIC: &[u8; 8] = b"DSIMSAVE";
const VERSION: u32 = 2;

/// One command applied to a simulation since t = 0, as it was given to the world (a
/// grasp as asked, not as resolved: replaying it asks the world the same question).
#[derive(Clone, Debug, PartialEq)]
pub enum Entry {
    /// A step with these targets (empty: every handle scripted).
    Step(Vec<Option<Pose>>),
    /// `World::grasp(handle, object, at, hold)` that changed what the handle holds.
    Grasp {
        handle: usize,
        object: usize,
        at: GraspAt,
        hold: Option<Hold>,
    },
    /// `World::release(handle)` that let go of something.
    Release { handle: usize },
}

/// What a save holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Saved {
    pub text: String,
    pub file: String,
    pub overrides: Vec<String>,
    pub seed: u64,
    pub handles: usize,
    /// Every command since t = 0, in order.
    pub log: Vec<Entry>,
    /// [`fingerprint`] of the state after the last step.
    pub fingerprint: u64,
}

/// The bytes of `saved`.
pub fn encode(saved: &Saved) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    for s in [&saved.text, &saved.file] {
        put_str(&mut out, s);
    }
    out.extend_from_slice(&(saved.overrides.len() as u32).to_le_bytes());
    for s in &saved.overrides {
        put_str(&mut out, s);
    }
    out.extend_from_slice(&saved.seed.to_le_bytes());
    out.extend_from_slice(&(saved.handles as u32).to_le_bytes());
    out.extend_from_slice(&(saved.log.len() as u64).to_le_bytes());
    for entry in &saved.log {
        put_entry(&mut out, entry, saved.handles);
    }
    out.extend_from_slice(&saved.fingerprint.to_le_bytes());
    out
}

fn put_entry(out: &mut Vec<u8>, entry: &Entry, handles: usize) {
    let put_f64s = |out: &mut Vec<u8>, xs: &[f64]| {
        for x in xs {
            out.extend_from_slice(&x.to_bits().to_le_bytes());
        }
    };
    match entry {
        Entry::Step(targets) => {
            out.push(0);
            for h in 0..handles {
                match targets.get(h).copied().flatten() {
                    None => out.push(0),
                    Some(pose) => {
                        out.push(1);
                        let t = pose.translation.vector;
                        let q = pose.rotation.coords;
                        put_f64s(out, &[t.x, t.y, t.z, q.x, q.y, q.z, q.w]);
                    }
                }
            }
        }
        Entry::Grasp {
            handle,
            object,
            at,
            hold,
        } => {
            out.push(1);
            out.extend_from_slice(&(*handle as u32).to_le_bytes());
            out.extend_from_slice(&(*object as u32).to_le_bytes());
            match at {
                GraspAt::Material(m) => {
                    out.push(0);
                    put_f64s(out, &[m.x, m.y]);
                }
                GraspAt::Nearest {
                    point,
                    max_distance,
                } => {
                    out.push(1);
                    put_f64s(out, &[point.x, point.y, point.z, *max_distance]);
                }
            }
            match hold {
                None => out.push(0),
                Some(Hold::Position) => out.push(1),
                Some(Hold::Normal { stiffness }) => {
                    out.push(2);
                    put_f64s(out, &[*stiffness]);
                }
                Some(Hold::Full) => out.push(3),
            }
        }
        Entry::Release { handle } => {
            out.push(2);
            out.extend_from_slice(&(*handle as u32).to_le_bytes());
        }
    }
}

/// Read bytes written by [`encode`].
pub fn decode(bytes: &[u8]) -> Result<Saved, String> {
    let mut r = Reader { bytes, at: 0 };
    if r.take(8)? != MAGIC {
        return Err("not a saved developable_sim simulation (no DSIMSAVE header)".into());
    }
    let version = r.u32()?;
    if version != VERSION {
        return Err(format!(
            "saved with format version {version}; this build reads version {VERSION}"
        ));
    }
    let text = r.string()?;
    let file = r.string()?;
    let n = r.u32()? as usize;
    let overrides = (0..n).map(|_| r.string()).collect::<Result<Vec<_>, _>>()?;
    let seed = r.u64()?;
    let handles = r.u32()? as usize;
    let commands = r.u64()? as usize;
    // at least a byte per command: refuse absurd counts before allocating
    if commands > bytes.len() {
        return Err("truncated: fewer bytes than the command count needs".into());
    }
    let mut log = Vec::with_capacity(commands);
    for _ in 0..commands {
        log.push(match r.take(1)?[0] {
            0 => Entry::Step(r.targets(handles)?),
            1 => r.grasp(handles)?,
            2 => Entry::Release {
                handle: r.handle(handles)?,
            },
            k => return Err(format!("bad command kind {k}")),
        });
    }
    let fingerprint = r.u64()?;
    if r.at != bytes.len() {
        return Err(format!("{} bytes after the end", bytes.len() - r.at));
    }
    Ok(Saved {
        text,
        file,
        overrides,
        seed,
        handles,
        log,
        fingerprint,
    })
}

/// FNV-1a over the bits of the world's time, step count, every object's mesh vertices
/// and what each handle holds (attached, object, material point, generation): equal
/// fingerprints of a replayed and a saved world mean the replay reached the same state
/// (up to a 64-bit hash collision).
pub fn fingerprint(world: &World) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    eat(world.time().to_bits());
    eat(world.steps_taken());
    for o in 0..world.objects().len() {
        for p in &world.mesh(o).vertices {
            for x in p.coords.iter() {
                eat(x.to_bits());
            }
        }
    }
    for spec in world.handles() {
        eat(spec.attached as u64);
        eat(spec.object as u64);
        eat(spec.material_point.x.to_bits());
        eat(spec.material_point.y.to_bits());
        eat(spec.generation);
    }
    h
}

fn put_str(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| format!("truncated at byte {}", self.at))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn string(&mut self) -> Result<String, String> {
        let n = self.u32()? as usize;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| "a string is not UTF-8".into())
    }
    fn f64s<const N: usize>(&mut self) -> Result<[f64; N], String> {
        let mut x = [0.0; N];
        for v in &mut x {
            *v = self.f64()?;
        }
        Ok(x)
    }
    /// One step's targets, one tag per handle; all scripted is stored as an empty
    /// list (as stepped).
    fn targets(&mut self, handles: usize) -> Result<Vec<Option<Pose>>, String> {
        let mut step = Vec::with_capacity(handles);
        for _ in 0..handles {
            step.push(match self.take(1)?[0] {
                0 => None,
                1 => Some(self.pose()?),
                tag => return Err(format!("bad target tag {tag}")),
            });
        }
        if step.iter().all(Option::is_none) {
            step.clear();
        }
        Ok(step)
    }
    /// A handle index below `handles`.
    fn handle(&mut self, handles: usize) -> Result<usize, String> {
        let h = self.u32()? as usize;
        if h >= handles {
            return Err(format!("handle {h} of {handles}"));
        }
        Ok(h)
    }
    fn grasp(&mut self, handles: usize) -> Result<Entry, String> {
        let handle = self.handle(handles)?;
        let object = self.u32()? as usize;
        let at = match self.take(1)?[0] {
            0 => {
                let [u, v] = self.f64s()?;
                GraspAt::Material(Point2::new(u, v))
            }
            1 => {
                let [x, y, z, max_distance] = self.f64s()?;
                GraspAt::Nearest {
                    point: Point3::new(x, y, z),
                    max_distance,
                }
            }
            tag => return Err(format!("bad grasp point tag {tag}")),
        };
        let hold = match self.take(1)?[0] {
            0 => None,
            1 => Some(Hold::Position),
            2 => Some(Hold::Normal {
                stiffness: self.f64()?,
            }),
            3 => Some(Hold::Full),
            tag => return Err(format!("bad hold tag {tag}")),
        };
        Ok(Entry::Grasp {
            handle,
            object,
            at,
            hold,
        })
    }
    /// A pose as stored: the quaternion's bits exactly (no renormalization).
    fn pose(&mut self) -> Result<Pose, String> {
        let x: [f64; 7] = self.f64s()?;
        let q = UnitQuaternion::new_unchecked(Quaternion::new(x[6], x[3], x[4], x[5]));
        Ok(Pose::from_parts(Translation3::new(x[0], x[1], x[2]), q))
    }
}
