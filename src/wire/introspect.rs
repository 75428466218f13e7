//! A serde serializer that turns any message into a [`Value`] tree (struct and field
//! names, sequences, numbers). Used to compare recorded and recomputed messages
//! (replay) and to check the Rust structs against the `.msg` files (tests).

use serde::ser::{self, Serialize};

/// A message as a tree of values.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Bool(bool),
    /// Signed integer with its `.msg` type (`int8` .. `int64`).
    Int(i64, &'static str),
    /// Unsigned integer with its `.msg` type (`uint8` .. `uint64`).
    UInt(u64, &'static str),
    /// Floating point with its `.msg` type (`float32`, `float64`).
    Float(f64, &'static str),
    Str(String),
    /// A sequence `T[]`.
    Seq(Vec<Value>),
    /// A fixed-size array `T[N]`.
    Array(Vec<Value>),
    /// A struct: the Rust type name and its fields in order.
    Struct(&'static str, Vec<(&'static str, Value)>),
}

impl Value {
    /// The `.msg` primitive type of a leaf (`None` for containers).
    pub fn primitive(&self) -> Option<&'static str> {
        match self {
            Value::Bool(_) => Some("bool"),
            Value::Int(_, t) | Value::UInt(_, t) | Value::Float(_, t) => Some(t),
            Value::Str(_) => Some("string"),
            _ => None,
        }
    }

    /// The named field of a struct value.
    pub fn field(&self, name: &str) -> Option<&Value> {
        match self {
            Value::Struct(_, fields) => fields.iter().find(|(n, _)| *n == name).map(|(_, v)| v),
            _ => None,
        }
    }

    /// Set a numeric field (by dotted path) to zero: used to drop wall-clock fields
    /// before comparing.
    pub fn zero_field(&mut self, path: &str) {
        let (head, rest) = match path.split_once('.') {
            Some((h, r)) => (h, Some(r)),
            None => (path, None),
        };
        if let Value::Struct(_, fields) = self {
            for (n, v) in fields.iter_mut() {
                if *n == head {
                    match rest {
                        Some(r) => v.zero_field(r),
                        None => {
                            let zero = match &*v {
                                Value::Int(_, t) => Value::Int(0, t),
                                Value::UInt(_, t) => Value::UInt(0, t),
                                Value::Float(_, t) => Value::Float(0.0, t),
                                Value::Bool(_) => Value::Bool(false),
                                other => other.clone(),
                            };
                            *v = zero;
                        }
                    }
                }
            }
        }
    }
}

/// The differences found between two values.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Difference {
    /// Numeric leaves whose bits differ (floats by `f64::to_bits`: -0.0 and +0.0
    /// differ, and so do NaNs with different bits; integers exactly).
    pub leaves: u64,
    /// Path of the first such leaf, e.g. `markers[0].points[12].x`.
    pub first_path: String,
    /// Largest absolute difference of a numeric leaf: 0 when the only differences are
    /// in the sign of zero or a NaN's bits, infinite when one side is not finite.
    pub max_abs: f64,
    /// Path of that leaf (empty when `max_abs` is 0).
    pub max_path: String,
    /// Structural differences (lengths, strings, types): the first one found.
    pub structural: Option<String>,
}

impl Difference {
    /// True when the two values are identical bit for bit.
    pub fn is_zero(&self) -> bool {
        self.leaves == 0 && self.structural.is_none()
    }

    /// A numeric leaf at `path` differs by `magnitude`.
    fn note(&mut self, path: &str, magnitude: f64) {
        if self.leaves == 0 {
            self.first_path = path.to_string();
        }
        self.leaves += 1;
        if magnitude > self.max_abs {
            self.max_abs = magnitude;
            self.max_path = path.to_string();
        }
    }
}

/// Compare two values: the largest numeric difference and the first structural one.
pub fn compare(a: &Value, b: &Value) -> Difference {
    let mut d = Difference::default();
    walk(a, b, &mut String::new(), &mut d);
    d
}

fn note_structural(d: &mut Difference, path: &str, what: String) {
    if d.structural.is_none() {
        d.structural = Some(format!(
            "{}: {what}",
            if path.is_empty() { "." } else { path }
        ));
    }
}

fn walk(a: &Value, b: &Value, path: &mut String, d: &mut Difference) {
    match (a, b) {
        (Value::Struct(na, fa), Value::Struct(nb, fb)) => {
            if na != nb || fa.len() != fb.len() {
                note_structural(d, path, format!("type {na} vs {nb}"));
                return;
            }
            for ((ka, va), (_, vb)) in fa.iter().zip(fb) {
                let len = path.len();
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(ka);
                walk(va, vb, path, d);
                path.truncate(len);
            }
        }
        (Value::Seq(xa), Value::Seq(xb)) | (Value::Array(xa), Value::Array(xb)) => {
            if xa.len() != xb.len() {
                note_structural(d, path, format!("{} vs {} elements", xa.len(), xb.len()));
                return;
            }
            for (i, (va, vb)) in xa.iter().zip(xb).enumerate() {
                let len = path.len();
                path.push_str(&format!("[{i}]"));
                walk(va, vb, path, d);
                path.truncate(len);
            }
        }
        (Value::Str(sa), Value::Str(sb)) => {
            if sa != sb {
                note_structural(d, path, format!("{sa:?} vs {sb:?}"));
            }
        }
        _ => match leaf_difference(a, b) {
            Some(None) => {}
            Some(Some(magnitude)) => d.note(path, magnitude),
            None => note_structural(d, path, format!("{a:?} vs {b:?}")),
        },
    }
}

/// Compare two numeric leaves of the same type bit for bit: `Some(None)` when
/// identical, `Some(Some(|a - b|))` when not (0 for -0.0 vs +0.0 or two NaNs with
/// different bits, infinite when one side is not finite), `None` when they are not
/// numbers of the same type.
fn leaf_difference(a: &Value, b: &Value) -> Option<Option<f64>> {
    let magnitude = match (a, b) {
        (Value::Float(x, ta), Value::Float(y, tb)) if ta == tb => {
            if x.to_bits() == y.to_bits() {
                return Some(None);
            }
            if x.is_finite() && y.is_finite() {
                (x - y).abs()
            } else if x.is_nan() && y.is_nan() {
                0.0
            } else {
                f64::INFINITY
            }
        }
        (Value::Int(x, ta), Value::Int(y, tb)) if ta == tb => {
            if x == y {
                return Some(None);
            }
            (*x as i128 - *y as i128).unsigned_abs() as f64
        }
        (Value::UInt(x, ta), Value::UInt(y, tb)) if ta == tb => {
            if x == y {
                return Some(None);
            }
            x.abs_diff(*y) as f64
        }
        (Value::Bool(x), Value::Bool(y)) => {
            if x == y {
                return Some(None);
            }
            1.0
        }
        _ => return None,
    };
    Some(Some(magnitude))
}

/// Serialize `value` into a [`Value`] tree.
pub fn to_value<T: Serialize + ?Sized>(value: &T) -> Result<Value, Error> {
    value.serialize(ValueSerializer)
}

/// An unsupported serde construct (messages are plain structs, sequences and numbers).
#[derive(Debug, thiserror::Error)]
#[error("introspection: {0}")]
pub struct Error(String);

impl ser::Error for Error {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        Error(msg.to_string())
    }
}

struct ValueSerializer;

pub struct SeqBuilder {
    items: Vec<Value>,
    fixed: bool,
}

pub struct StructBuilder {
    name: &'static str,
    fields: Vec<(&'static str, Value)>,
}

fn unsupported(what: &str) -> Error {
    Error(format!("{what} is not a ROS message construct"))
}

impl ser::Serializer for ValueSerializer {
    type Ok = Value;
    type Error = Error;
    type SerializeSeq = SeqBuilder;
    type SerializeTuple = SeqBuilder;
    type SerializeTupleStruct = SeqBuilder;
    type SerializeTupleVariant = ser::Impossible<Value, Error>;
    type SerializeMap = ser::Impossible<Value, Error>;
    type SerializeStruct = StructBuilder;
    type SerializeStructVariant = ser::Impossible<Value, Error>;

    fn serialize_bool(self, v: bool) -> Result<Value, Error> {
        Ok(Value::Bool(v))
    }
    fn serialize_i8(self, v: i8) -> Result<Value, Error> {
        Ok(Value::Int(v as i64, "int8"))
    }
    fn serialize_i16(self, v: i16) -> Result<Value, Error> {
        Ok(Value::Int(v as i64, "int16"))
    }
    fn serialize_i32(self, v: i32) -> Result<Value, Error> {
        Ok(Value::Int(v as i64, "int32"))
    }
    fn serialize_i64(self, v: i64) -> Result<Value, Error> {
        Ok(Value::Int(v, "int64"))
    }
    fn serialize_u8(self, v: u8) -> Result<Value, Error> {
        Ok(Value::UInt(v as u64, "uint8"))
    }
    fn serialize_u16(self, v: u16) -> Result<Value, Error> {
        Ok(Value::UInt(v as u64, "uint16"))
    }
    fn serialize_u32(self, v: u32) -> Result<Value, Error> {
        Ok(Value::UInt(v as u64, "uint32"))
    }
    fn serialize_u64(self, v: u64) -> Result<Value, Error> {
        Ok(Value::UInt(v, "uint64"))
    }
    fn serialize_f32(self, v: f32) -> Result<Value, Error> {
        Ok(Value::Float(v as f64, "float32"))
    }
    fn serialize_f64(self, v: f64) -> Result<Value, Error> {
        Ok(Value::Float(v, "float64"))
    }
    fn serialize_char(self, _: char) -> Result<Value, Error> {
        Err(unsupported("char"))
    }
    fn serialize_str(self, v: &str) -> Result<Value, Error> {
        Ok(Value::Str(v.to_string()))
    }
    fn serialize_bytes(self, v: &[u8]) -> Result<Value, Error> {
        Ok(Value::Seq(
            v.iter().map(|b| Value::UInt(*b as u64, "uint8")).collect(),
        ))
    }
    fn serialize_none(self) -> Result<Value, Error> {
        Err(unsupported("Option"))
    }
    fn serialize_some<T: Serialize + ?Sized>(self, _: &T) -> Result<Value, Error> {
        Err(unsupported("Option"))
    }
    fn serialize_unit(self) -> Result<Value, Error> {
        Err(unsupported("()"))
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result<Value, Error> {
        Ok(Value::Struct(name, Vec::new()))
    }
    fn serialize_unit_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
    ) -> Result<Value, Error> {
        Err(unsupported("enum"))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        value: &T,
    ) -> Result<Value, Error> {
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<Value, Error> {
        Err(unsupported("enum"))
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<SeqBuilder, Error> {
        Ok(SeqBuilder {
            items: Vec::with_capacity(len.unwrap_or(0)),
            fixed: false,
        })
    }
    fn serialize_tuple(self, len: usize) -> Result<SeqBuilder, Error> {
        Ok(SeqBuilder {
            items: Vec::with_capacity(len),
            fixed: true,
        })
    }
    fn serialize_tuple_struct(self, _: &'static str, len: usize) -> Result<SeqBuilder, Error> {
        self.serialize_tuple(len)
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, Error> {
        Err(unsupported("enum"))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, Error> {
        Err(unsupported("map"))
    }
    fn serialize_struct(self, name: &'static str, len: usize) -> Result<StructBuilder, Error> {
        Ok(StructBuilder {
            name,
            fields: Vec::with_capacity(len),
        })
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, Error> {
        Err(unsupported("enum"))
    }
}

impl ser::SerializeSeq for SeqBuilder {
    type Ok = Value;
    type Error = Error;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        self.items.push(value.serialize(ValueSerializer)?);
        Ok(())
    }
    fn end(self) -> Result<Value, Error> {
        Ok(if self.fixed {
            Value::Array(self.items)
        } else {
            Value::Seq(self.items)
        })
    }
}

impl ser::SerializeTuple for SeqBuilder {
    type Ok = Value;
    type Error = Error;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        ser::SerializeSeq::serialize_element(self, value)
    }
    fn end(self) -> Result<Value, Error> {
        ser::SerializeSeq::end(self)
    }
}

impl ser::SerializeTupleStruct for SeqBuilder {
    type Ok = Value;
    type Error = Error;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        ser::SerializeSeq::serialize_element(self, value)
    }
    fn end(self) -> Result<Value, Error> {
        ser::SerializeSeq::end(self)
    }
}

impl ser::SerializeStruct for StructBuilder {
    type Ok = Value;
    type Error = Error;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), Error> {
        self.fields.push((key, value.serialize(ValueSerializer)?));
        Ok(())
    }
    fn end(self) -> Result<Value, Error> {
        Ok(Value::Struct(self.name, self.fields))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::msgs::{Point, SingularPoint, SingularPoints};

    #[test]
    fn compare_is_bit_exact() {
        let f = |x: f64| Value::Float(x, "float64");
        let same = |a: &Value, b: &Value| compare(a, b).is_zero();
        assert!(same(&f(1.5), &f(1.5)));
        // the sign of zero
        let d = compare(&f(0.0), &f(-0.0));
        assert!(!d.is_zero());
        assert_eq!((d.leaves, d.max_abs), (1, 0.0));
        // NaNs: the same bits are identical, different bits are not
        let quiet = f64::NAN;
        let other = f64::from_bits(quiet.to_bits() | 1);
        assert!(other.is_nan());
        assert!(same(&f(quiet), &f(quiet)));
        assert!(!same(&f(quiet), &f(other)));
        assert!(!same(&f(quiet), &f(-quiet)));
        assert_eq!(compare(&f(quiet), &f(1.0)).max_abs, f64::INFINITY);
        // integers beyond 2^53 are compared exactly, not through f64
        let big = 1u64 << 60;
        let d = compare(&Value::UInt(big, "uint64"), &Value::UInt(big + 1, "uint64"));
        assert_eq!((d.leaves, d.max_abs), (1, 1.0));
        let d = compare(
            &Value::Int(i64::MIN, "int64"),
            &Value::Int(i64::MAX, "int64"),
        );
        assert!(!d.is_zero() && d.max_abs > 1e19);
        // the first differing leaf is named even when the magnitude is 0
        let mut a = SingularPoints::default();
        a.points.push(SingularPoint::default());
        let mut b = a.clone();
        b.points[0].position.z = -0.0;
        let d = compare(&to_value(&a).unwrap(), &to_value(&b).unwrap());
        assert_eq!(d.first_path, "points[0].position.z");
        assert!(!d.is_zero());
    }

    #[test]
    fn compare_finds_the_largest_difference_and_structure_changes() {
        let mut a = SingularPoints::default();
        a.points.push(SingularPoint {
            id: 3,
            position: Point {
                x: 1.0,
                y: 2.0,
                z: 3.0,
            },
            material: [0.5, 0.0],
        });
        let mut b = a.clone();
        assert!(compare(&to_value(&a).unwrap(), &to_value(&b).unwrap()).is_zero());
        b.points[0].position.y += 1e-3;
        b.points[0].material[0] += 1e-6;
        let d = compare(&to_value(&a).unwrap(), &to_value(&b).unwrap());
        assert!((d.max_abs - 1e-3).abs() < 1e-12);
        assert_eq!(d.max_path, "points[0].position.y");
        assert!(d.structural.is_none());
        b.points.clear();
        let d = compare(&to_value(&a).unwrap(), &to_value(&b).unwrap());
        assert!(d.structural.unwrap().contains("1 vs 0"));
        let mut v = to_value(&a).unwrap();
        v.zero_field("header.stamp.sec");
        assert_eq!(
            v.field("header")
                .unwrap()
                .field("stamp")
                .unwrap()
                .field("sec"),
            Some(&Value::Int(0, "int32"))
        );
    }
}
