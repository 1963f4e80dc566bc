//! Fixed-size logged messages declared once: [`record!`](crate::record!) makes the struct,
//! its format string, its size and its little-endian encoding and decoding from one field
//! list, so the bytes a writer logs and the format that describes them cannot drift apart.

use crate::Error;

/// A field type a record may hold: the basic types and fixed arrays of them.
pub trait Field: Sized {
    /// Encoded size in bytes.
    const SIZE: usize;
    /// Writes the value at the start of `out` (exactly [`Field::SIZE`] bytes; the record's
    /// encoder hands each field its own slice).
    fn put(&self, out: &mut [u8]);
    /// Reads a value from the start of `bytes`.
    ///
    /// # Errors
    /// [`Error::Layout`] if `bytes` is shorter than [`Field::SIZE`].
    fn get(bytes: &[u8]) -> Result<Self, Error>;
}

macro_rules! numeric_field {
    ($($t:ty),*) => {$(
        impl Field for $t {
            const SIZE: usize = core::mem::size_of::<$t>();
            fn put(&self, out: &mut [u8]) {
                if let Some(o) = out.get_mut(..Self::SIZE) {
                    o.copy_from_slice(&self.to_le_bytes());
                }
            }
            fn get(bytes: &[u8]) -> Result<Self, Error> {
                let b = bytes.get(..Self::SIZE).ok_or(Error::Layout)?;
                let mut a = [0u8; core::mem::size_of::<$t>()];
                a.copy_from_slice(b);
                Ok(<$t>::from_le_bytes(a))
            }
        }
    )*};
}

numeric_field!(u8, i8, u16, i16, u32, i32, u64, i64, f32, f64);

impl Field for bool {
    const SIZE: usize = 1;
    fn put(&self, out: &mut [u8]) {
        u8::from(*self).put(out);
    }
    fn get(bytes: &[u8]) -> Result<Self, Error> {
        Ok(u8::get(bytes)? != 0)
    }
}

impl<T: Field + Copy + Default, const N: usize> Field for [T; N] {
    const SIZE: usize = T::SIZE * N;
    fn put(&self, out: &mut [u8]) {
        for (v, o) in self.iter().zip(out.chunks_mut(T::SIZE)) {
            v.put(o);
        }
    }
    fn get(bytes: &[u8]) -> Result<Self, Error> {
        let bytes = bytes.get(..Self::SIZE).ok_or(Error::Layout)?;
        let mut out = [T::default(); N];
        for (v, b) in out.iter_mut().zip(bytes.chunks(T::SIZE)) {
            *v = T::get(b)?;
        }
        Ok(out)
    }
}

/// A fixed-size logged message (declare one with [`record!`](crate::record!)).
pub trait Record: Sized {
    /// The message name (`"sensor_imu"`).
    const NAME: &'static str;
    /// The whole format string, `NAME:uint64_t timestamp;…`.
    const FORMAT: &'static str;
    /// The encoded size in bytes, timestamp included.
    const SIZE: usize;
    /// The timestamp, µs.
    fn timestamp_us(&self) -> u64;
    /// Writes the record into `out[..SIZE]`.
    ///
    /// # Errors
    /// [`Error::Full`] if `out` is shorter than [`Record::SIZE`].
    fn encode(&self, out: &mut [u8]) -> Result<(), Error>;
    /// Reads a record from exactly [`Record::SIZE`] bytes.
    ///
    /// # Errors
    /// [`Error::Layout`] for any other length.
    fn decode(bytes: &[u8]) -> Result<Self, Error>;
}

/// The ULog type name of a field type written as tokens: `f32` → `"float"`,
/// `[f32; 3]` → `"float[3]"`.
#[doc(hidden)]
#[macro_export]
macro_rules! ulog_type {
    (u8) => {
        "uint8_t"
    };
    (i8) => {
        "int8_t"
    };
    (u16) => {
        "uint16_t"
    };
    (i16) => {
        "int16_t"
    };
    (u32) => {
        "uint32_t"
    };
    (i32) => {
        "int32_t"
    };
    (u64) => {
        "uint64_t"
    };
    (i64) => {
        "int64_t"
    };
    (f32) => {
        "float"
    };
    (f64) => {
        "double"
    };
    (bool) => {
        "bool"
    };
    ([$t:tt; $n:literal]) => {
        concat!($crate::ulog_type!($t), "[", $n, "]")
    };
}

/// Declares a logged message: a struct with a `timestamp: u64` (µs) first and the listed
/// fields after it, implementing [`Record`]. Field types are the basic types (`u8` … `f64`,
/// `bool`) and fixed arrays of them, written as tokens (`[f32; 3]`).
///
/// ```
/// taulink_ulog::record! {
///     /// One barometer reading.
///     pub struct Baro = "sensor_baro" {
///         /// Altitude, m.
///         pub altitude_m: f32,
///         /// Reading counter.
///         pub count: [u16; 2],
///     }
/// }
/// use taulink_ulog::Record;
/// assert_eq!(Baro::FORMAT, "sensor_baro:uint64_t timestamp;float altitude_m;uint16_t[2] count;");
/// assert_eq!(Baro::SIZE, 16);
/// let b = Baro { timestamp: 5, altitude_m: 1.5, count: [1, 2] };
/// let mut bytes = [0u8; 16];
/// b.encode(&mut bytes).unwrap();
/// assert_eq!(Baro::decode(&bytes), Ok(b));
/// ```
#[macro_export]
macro_rules! record {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident = $ulog:literal {
            $( $(#[$fmeta:meta])* $fvis:vis $field:ident : $t:tt ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        $vis struct $name {
            /// Time of the sample, µs.
            pub timestamp: u64,
            $( $(#[$fmeta])* $fvis $field: $t, )*
        }

        impl $crate::Record for $name {
            const NAME: &'static str = $ulog;
            const FORMAT: &'static str = concat!(
                $ulog, ":uint64_t timestamp;",
                $( $crate::ulog_type!($t), " ", stringify!($field), ";", )*
            );
            const SIZE: usize = 8 $( + <$t as $crate::Field>::SIZE )*;

            fn timestamp_us(&self) -> u64 {
                self.timestamp
            }

            fn encode(&self, out: &mut [u8]) -> Result<(), $crate::Error> {
                let out = out.get_mut(..Self::SIZE).ok_or($crate::Error::Full)?;
                let (head, rest) = out.split_at_mut(8);
                $crate::Field::put(&self.timestamp, head);
                $(
                    let (head, rest) = rest.split_at_mut(<$t as $crate::Field>::SIZE);
                    $crate::Field::put(&self.$field, head);
                )*
                let _ = rest;
                Ok(())
            }

            fn decode(bytes: &[u8]) -> Result<Self, $crate::Error> {
                if bytes.len() != Self::SIZE {
                    return Err($crate::Error::Layout);
                }
                let timestamp = <u64 as $crate::Field>::get(bytes)?;
                let rest = bytes.get(8..).ok_or($crate::Error::Layout)?;
                $(
                    let $field = <$t as $crate::Field>::get(rest)?;
                    let rest = rest
                        .get(<$t as $crate::Field>::SIZE..)
                        .ok_or($crate::Error::Layout)?;
                )*
                let _ = rest;
                Ok(Self { timestamp, $( $field, )* })
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use crate::Record;
    use crate::format::Format;

    crate::record! {
        /// Every field kind.
        struct All = "all_kinds" {
            a: u8, b: i8, c: u16, d: i16, e: u32, f: i32, g: u64, h: i64,
            i: f32, j: f64, k: bool, l: [f32; 3], m: [u8; 2],
        }
    }

    #[test]
    fn the_format_describes_the_encoding() {
        let f = Format::parse(All::FORMAT).unwrap();
        assert_eq!(f.size(), Ok(All::SIZE));
        assert_eq!(
            All::SIZE,
            8 + 1 + 1 + 2 + 2 + 4 + 4 + 8 + 8 + 4 + 8 + 1 + 12 + 2
        );
        let v = All {
            timestamp: 0x0102_0304_0506_0708,
            a: 200,
            b: -3,
            c: 60_000,
            d: -2,
            e: 4_000_000_000,
            f: -40,
            g: u64::MAX - 1,
            h: i64::MIN,
            i: -1.25,
            j: 1e300,
            k: true,
            l: [1.0, -2.0, f32::MAX],
            m: [7, 9],
        };
        let mut bytes = vec![0u8; All::SIZE];
        v.encode(&mut bytes).unwrap();
        // Each field sits at the offset the format gives it, little endian.
        let (off, _) = f.field("c").unwrap();
        assert_eq!(bytes[off..off + 2], 60_000u16.to_le_bytes());
        let (off, _) = f.field("l").unwrap();
        assert_eq!(bytes[off + 4..off + 8], (-2.0f32).to_le_bytes());
        assert_eq!(bytes[..8], [8, 7, 6, 5, 4, 3, 2, 1]);
        assert_eq!(All::decode(&bytes), Ok(v));
        assert_eq!(All::decode(&bytes[1..]), Err(crate::Error::Layout));
        assert_eq!(v.encode(&mut [0u8; 10]), Err(crate::Error::Full));
    }
}
