//! The text side of ULog: format strings (`name:type field;type[n] field;…`), information
//! and parameter keys (`type name`), the basic types with their sizes, and typed values read
//! from little-endian bytes. Everything here takes untrusted text and returns an error for
//! anything the specification does not allow.

use crate::Error;

/// The basic binary types and their C names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basic {
    /// `int8_t`
    I8,
    /// `uint8_t`
    U8,
    /// `int16_t`
    I16,
    /// `uint16_t`
    U16,
    /// `int32_t`
    I32,
    /// `uint32_t`
    U32,
    /// `int64_t`
    I64,
    /// `uint64_t`
    U64,
    /// `float`
    F32,
    /// `double`
    F64,
    /// `bool`
    Bool,
    /// `char`
    Char,
}

/// Each basic type with its C name, in one table.
const BASICS: [(Basic, &str); 12] = [
    (Basic::I8, "int8_t"),
    (Basic::U8, "uint8_t"),
    (Basic::I16, "int16_t"),
    (Basic::U16, "uint16_t"),
    (Basic::I32, "int32_t"),
    (Basic::U32, "uint32_t"),
    (Basic::I64, "int64_t"),
    (Basic::U64, "uint64_t"),
    (Basic::F32, "float"),
    (Basic::F64, "double"),
    (Basic::Bool, "bool"),
    (Basic::Char, "char"),
];

impl Basic {
    /// Size in bytes.
    pub const fn size(self) -> usize {
        match self {
            Basic::I8 | Basic::U8 | Basic::Bool | Basic::Char => 1,
            Basic::I16 | Basic::U16 => 2,
            Basic::I32 | Basic::U32 | Basic::F32 => 4,
            Basic::I64 | Basic::U64 | Basic::F64 => 8,
        }
    }

    /// The C name (`"float"`).
    pub fn name(self) -> &'static str {
        BASICS
            .iter()
            .find(|(b, _)| *b == self)
            .map_or("", |(_, n)| n)
    }

    /// The basic type of a C name, if it is one.
    pub fn from_name(name: &str) -> Option<Self> {
        BASICS.iter().find(|(_, n)| *n == name).map(|(b, _)| *b)
    }
}

/// A field's or key's type: a type name (basic or another format's), optionally an array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TypeRef<'a> {
    /// The type name as written (`"float"`, or a nested format's name).
    pub name: &'a str,
    /// The basic type, if the name is one.
    pub basic: Option<Basic>,
    /// The array length, for `type[n]`.
    pub array: Option<u16>,
}

impl<'a> TypeRef<'a> {
    /// Parses `type` or `type[n]`.
    ///
    /// # Errors
    /// [`Error::InvalidText`] for an empty or ill-formed name, a bad array length.
    pub fn parse(text: &'a str) -> Result<Self, Error> {
        let (name, array) = match text.split_once('[') {
            Some((name, rest)) => {
                let digits = rest.strip_suffix(']').ok_or(Error::InvalidText)?;
                let n: u16 = parse_decimal(digits).ok_or(Error::InvalidText)?;
                (name, Some(n))
            }
            None => (text, None),
        };
        if !is_message_name(name) {
            return Err(Error::InvalidText);
        }
        Ok(Self {
            name,
            basic: Basic::from_name(name),
            array,
        })
    }

    /// How many elements (1 for a scalar).
    pub fn count(&self) -> usize {
        self.array.map_or(1, usize::from)
    }

    /// Size in bytes of a basic type (or array of one).
    ///
    /// # Errors
    /// [`Error::Nested`] for another format's name.
    pub fn size(&self) -> Result<usize, Error> {
        let basic = self.basic.ok_or(Error::Nested)?;
        Ok(basic.size() * self.count())
    }
}

/// A decimal number of ASCII digits only (no sign, no spaces), if it fits.
fn parse_decimal(digits: &str) -> Option<u16> {
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// `a-zA-Z0-9_-/`, non-empty: message names and information keys.
pub fn is_message_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'/'))
}

/// `a-zA-Z0-9_`, non-empty: field names.
pub fn is_field_name(name: &str) -> bool {
    !name.is_empty() && name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
}

/// One field of a format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldDef<'a> {
    /// Its type.
    pub ty: TypeRef<'a>,
    /// Its name.
    pub name: &'a str,
}

impl FieldDef<'_> {
    /// A `_padding…` field: not shown, its data ignored.
    pub fn is_padding(&self) -> bool {
        self.name.starts_with("_padding")
    }
}

/// A parsed format message: `name:type field;…`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Format<'a> {
    /// The message name.
    pub name: &'a str,
    fields: &'a str,
}

impl<'a> Format<'a> {
    /// Parses and checks a whole format string (every field is checked here, so
    /// [`Format::fields`] never meets a bad one).
    ///
    /// # Errors
    /// [`Error::InvalidText`]: no `:`, a bad message or field name or type, no field, a
    /// message named like a basic type.
    pub fn parse(text: &'a str) -> Result<Self, Error> {
        let (name, fields) = text.split_once(':').ok_or(Error::InvalidText)?;
        if !is_message_name(name) || Basic::from_name(name).is_some() {
            return Err(Error::InvalidText);
        }
        let format = Self { name, fields };
        let mut count = 0usize;
        for field in format.split() {
            field?;
            count += 1;
        }
        if count == 0 {
            return Err(Error::InvalidText);
        }
        Ok(format)
    }

    fn split(&self) -> impl Iterator<Item = Result<FieldDef<'a>, Error>> + 'a {
        self.fields.split(';').filter(|f| !f.is_empty()).map(|f| {
            let (ty, name) = f.split_once(' ').ok_or(Error::InvalidText)?;
            if !is_field_name(name) {
                return Err(Error::InvalidText);
            }
            Ok(FieldDef {
                ty: TypeRef::parse(ty)?,
                name,
            })
        })
    }

    /// The fields in order.
    pub fn fields(&self) -> impl Iterator<Item = FieldDef<'a>> + 'a {
        self.split().filter_map(Result::ok)
    }

    /// Size of one message of this format in bytes, padding included.
    ///
    /// # Errors
    /// [`Error::Nested`] if a field has another format's type.
    pub fn size(&self) -> Result<usize, Error> {
        self.fields().try_fold(0usize, |n, f| Ok(n + f.ty.size()?))
    }

    /// Byte offset and type of the field `name`.
    ///
    /// # Errors
    /// [`Error::Nested`] if a field before it has another format's type; [`Error::Layout`]
    /// if there is no such field.
    pub fn field(&self, name: &str) -> Result<(usize, TypeRef<'a>), Error> {
        let mut offset = 0usize;
        for f in self.fields() {
            if f.name == name {
                return Ok((offset, f.ty));
            }
            offset += f.ty.size()?;
        }
        Err(Error::Layout)
    }
}

/// An information or parameter key: `type name`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Key<'a> {
    /// The value's type.
    pub ty: TypeRef<'a>,
    /// The key's name.
    pub name: &'a str,
}

impl<'a> Key<'a> {
    /// Parses `type name`.
    ///
    /// # Errors
    /// [`Error::InvalidText`] for a missing space, a bad type or name, a nested type.
    pub fn parse(text: &'a str) -> Result<Self, Error> {
        let (ty, name) = text.split_once(' ').ok_or(Error::InvalidText)?;
        let ty = TypeRef::parse(ty)?;
        if ty.basic.is_none() || !is_message_name(name) {
            return Err(Error::InvalidText);
        }
        Ok(Self { ty, name })
    }

    /// The value these bytes hold, for a scalar key.
    ///
    /// # Errors
    /// [`Error::Layout`] if the bytes are not exactly one value of the key's type, or the
    /// key is an array.
    pub fn scalar(&self, bytes: &[u8]) -> Result<Scalar, Error> {
        match (self.ty.basic, self.ty.array) {
            (Some(basic), None) if bytes.len() == basic.size() => Scalar::read(basic, bytes),
            _ => Err(Error::Layout),
        }
    }
}

/// One value of a basic type.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scalar {
    /// Any signed integer type, widened.
    Int(i64),
    /// Any unsigned integer type, widened.
    Uint(u64),
    /// `float`.
    F32(f32),
    /// `double`.
    F64(f64),
    /// `bool`.
    Bool(bool),
    /// `char`.
    Char(u8),
}

impl Scalar {
    /// Reads one value of `basic` from the start of `bytes`.
    ///
    /// # Errors
    /// [`Error::Layout`] if `bytes` is shorter than the type.
    pub fn read(basic: Basic, bytes: &[u8]) -> Result<Self, Error> {
        let b = bytes.get(..basic.size()).ok_or(Error::Layout)?;
        let mut w = [0u8; 8];
        w.get_mut(..b.len())
            .ok_or(Error::Layout)?
            .copy_from_slice(b);
        let u = u64::from_le_bytes(w);
        let sign = |bits: u32| ((u << (64 - bits)) as i64) >> (64 - bits);
        Ok(match basic {
            Basic::I8 => Scalar::Int(sign(8)),
            Basic::I16 => Scalar::Int(sign(16)),
            Basic::I32 => Scalar::Int(sign(32)),
            Basic::I64 => Scalar::Int(u as i64),
            Basic::U8 | Basic::U16 | Basic::U32 | Basic::U64 => Scalar::Uint(u),
            Basic::F32 => Scalar::F32(f32::from_bits(u as u32)),
            Basic::F64 => Scalar::F64(f64::from_bits(u)),
            Basic::Bool => Scalar::Bool(u != 0),
            Basic::Char => Scalar::Char(u as u8),
        })
    }

    /// The value as a double (integers converted, booleans 0/1).
    pub fn as_f64(self) -> f64 {
        match self {
            Scalar::Int(v) => v as f64,
            Scalar::Uint(v) => v as f64,
            Scalar::F32(v) => f64::from(v),
            Scalar::F64(v) => v,
            Scalar::Bool(v) => f64::from(u8::from(v)),
            Scalar::Char(v) => f64::from(v),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_format_gives_its_fields_offsets_and_size() {
        let f = Format::parse(
            "sensor_imu:uint64_t timestamp;float[3] gyro;uint8_t flags;uint8_t[3] _padding0;",
        )
        .unwrap();
        assert_eq!(f.name, "sensor_imu");
        assert_eq!(f.fields().count(), 4);
        assert_eq!(f.size(), Ok(8 + 12 + 1 + 3));
        let (offset, ty) = f.field("flags").unwrap();
        assert_eq!((offset, ty.basic, ty.array), (20, Some(Basic::U8), None));
        assert_eq!(f.field("gyro").unwrap().1.array, Some(3));
        assert!(f.fields().last().unwrap().is_padding());
        assert_eq!(f.field("nope"), Err(Error::Layout));
    }

    #[test]
    fn nested_types_parse_but_have_no_size_here() {
        let f = Format::parse("outer:uint64_t timestamp;inner[2] parts;").unwrap();
        assert_eq!(f.size(), Err(Error::Nested));
        assert_eq!(f.field("timestamp").unwrap().0, 0);
        assert_eq!(f.field("parts").unwrap().0, 8);
    }

    #[test]
    fn bad_formats_are_refused() {
        for text in [
            "",
            "noc olon",
            "name:",
            "float:uint8_t x;",
            "na me:uint8_t x;",
            "n:uint8_t;",
            "n:uint8_t x y;",
            "n:uint8_t[] x;",
            "n:uint8_t[70000] x;",
            "n:uint8_t[3 x;",
            "n:uint8_t[+3] x;",
            "n:uint8_t x-y;",
        ] {
            assert_eq!(Format::parse(text), Err(Error::InvalidText), "{text:?}");
        }
    }

    #[test]
    fn keys_read_their_values() {
        let k = Key::parse("int32_t link/bind_id").unwrap();
        assert_eq!(k.scalar(&(-5i32).to_le_bytes()), Ok(Scalar::Int(-5)));
        assert_eq!(k.scalar(&[1, 2]), Err(Error::Layout));
        let k = Key::parse("float pid/roll/kp").unwrap();
        assert_eq!(k.scalar(&0.25f32.to_le_bytes()), Ok(Scalar::F32(0.25)));
        let k = Key::parse("char[5] sys_name").unwrap();
        assert_eq!(k.ty.array, Some(5));
        assert_eq!(
            k.scalar(b"hello"),
            Err(Error::Layout),
            "an array is no scalar"
        );
        assert_eq!(Key::parse("int32_t"), Err(Error::InvalidText));
        assert_eq!(Key::parse("thing x"), Err(Error::InvalidText), "nested");
        assert_eq!(Key::parse("int32_t a.b"), Err(Error::InvalidText));
    }

    #[test]
    fn scalars_sign_extend_and_widen() {
        assert_eq!(Scalar::read(Basic::I8, &[0xFF]), Ok(Scalar::Int(-1)));
        assert_eq!(
            Scalar::read(Basic::I16, &[0x00, 0x80]),
            Ok(Scalar::Int(-32768))
        );
        assert_eq!(
            Scalar::read(Basic::U16, &[0x00, 0x80]),
            Ok(Scalar::Uint(32768))
        );
        assert_eq!(
            Scalar::read(Basic::F64, &1.5f64.to_le_bytes()),
            Ok(Scalar::F64(1.5))
        );
        assert_eq!(Scalar::read(Basic::Bool, &[2]), Ok(Scalar::Bool(true)));
        assert_eq!(Scalar::read(Basic::U32, &[1, 2, 3]), Err(Error::Layout));
        assert_eq!(Scalar::Int(-3).as_f64(), -3.0);
    }
}
