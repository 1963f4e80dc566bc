//! Typed handles to the table's rows, and the macro that declares the table and its handles
//! from one list. Code reads a setting as `settings.get(handles::RATE_MAX_DPS)` (an `f32`); a
//! misspelt handle does not compile, and a row declared as `f32` cannot be read as a `u32`
//! (the row builder's type must match the handle's). The dotted names stay for the console,
//! the `SettingChange` and the phone; code never looks one up.
//!
//! Each handle carries an accessor that indexes the value array with a *constant*, so an
//! index past the table fails to compile — there is no "wrong name reads 0.0" path left.

use core::marker::PhantomData;

use super::table::COUNT;
use super::{Param, Value};

/// What a setting's value is as a Rust type: `f32` for real-number rows, `u32` for
/// whole-number rows and choices (the choice's index).
pub trait ParamType: Copy {
    /// The 32 bits stored for `self` (what flash holds).
    fn to_bits(self) -> u32;
    /// The value from its stored bits.
    fn from_bits(bits: u32) -> Self;
    /// `self` as a table value.
    fn to_value(self) -> Value;
}

impl ParamType for f32 {
    fn to_bits(self) -> u32 {
        f32::to_bits(self)
    }
    fn from_bits(bits: u32) -> Self {
        f32::from_bits(bits)
    }
    fn to_value(self) -> Value {
        Value::F32(self)
    }
}

impl ParamType for u32 {
    fn to_bits(self) -> u32 {
        self
    }
    fn from_bits(bits: u32) -> Self {
        bits
    }
    fn to_value(self) -> Value {
        Value::U32(self)
    }
}

/// A table row of value type `T`, as the row builders (`f`, `u`, `c`) make it; the
/// declaring macro only accepts it for a handle of the same `T`.
pub(super) struct Row<T> {
    pub(super) param: Param,
    pub(super) _type: PhantomData<T>,
}

/// The row's parameter, if its type is `T` (a type mismatch does not compile).
pub(super) const fn typed<T>(row: Row<T>) -> Param {
    row.param
}

/// Every setting's stored bits, in table order (what a handle reads).
pub type Bits = [u32; COUNT];

/// A typed handle to one setting: its table index and a constant-index accessor.
#[derive(Clone, Copy)]
pub struct Handle<T> {
    pub(super) index: usize,
    pub(super) read: fn(&Bits) -> u32,
    pub(super) _type: PhantomData<T>,
}

impl<T> core::fmt::Debug for Handle<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_tuple("Handle").field(&self.index).finish()
    }
}

impl<T: ParamType> Handle<T> {
    /// The row this handle names.
    pub fn param(self) -> Option<&'static Param> {
        super::PARAMS.get(self.index)
    }

    /// Its row's index (the `SettingChange` id).
    pub fn index(self) -> usize {
        self.index
    }

    /// Its value in `bits`.
    pub fn read(self, bits: &Bits) -> T {
        T::from_bits((self.read)(bits))
    }

    /// A change setting this row to `value` (range-checked where it is applied).
    pub fn to(self, value: T) -> Change {
        Change {
            index: self.index,
            value: value.to_value(),
        }
    }
}

/// One setting change: which row and its new value (range-checked when applied).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Change {
    index: usize,
    value: Value,
}

impl Change {
    /// The change of the row named `name` to `value`; `None` for an unknown name.
    pub fn by_name(name: &str, value: Value) -> Option<Self> {
        super::find(name).map(|(index, _)| Self { index, value })
    }

    /// The row's index.
    pub fn index(&self) -> usize {
        self.index
    }

    /// The new value, unchecked.
    pub fn value(&self) -> Value {
        self.value
    }
}

/// Declares the table (`PARAMS`, `DOCS`) and one typed handle per row (in `handles`), from
/// one list of `/// doc` `HANDLE: type = row,` entries in table order; items after the `;`
/// join the handles module (the handle arrays of composite names). The table order is the
/// stored order and the `SettingChange` id, so rows are only ever appended.
macro_rules! table {
    ($( #[doc = $doc:literal] $handle:ident : $t:ty = $row:expr, )* ; $( $extra:item )*) => {
        /// Row positions, counted by the compiler from the list.
        #[allow(non_camel_case_types, clippy::upper_case_acronyms, dead_code)]
        #[repr(usize)]
        enum Index { $( $handle, )* }

        /// Every setting. Keys are grouped by hundreds per subsystem.
        pub const PARAMS: &[Param] = &[ $( $crate::settings::handle::typed::<$t>($row), )* ];

        /// Each row's meaning, in table order (a separate table, so firmware that never
        /// shows it links none of it).
        pub(super) const DOCS: &[&str] = &[ $( $doc.trim_ascii(), )* ];

        /// One typed handle per setting, named after its dotted name in capitals
        /// (`rate.max_dps` → `RATE_MAX_DPS`).
        pub mod handles {
            use core::marker::PhantomData;
            use $crate::settings::handle::Handle;
            $(
                #[doc = $doc]
                pub const $handle: Handle<$t> = Handle {
                    index: super::Index::$handle as usize,
                    read: |bits| {
                        const AT: usize = super::Index::$handle as usize;
                        // A constant index into a fixed-size array: checked when compiling.
                        bits[AT]
                    },
                    _type: PhantomData,
                };
            )*
            $( $extra )*
        }

        /// Every handle with its identifier, its index and whether its type fits its row.
        #[cfg(test)]
        pub(super) fn handle_rows() -> Vec<(&'static str, usize, bool)> {
            use $crate::settings::handle::fits;
            vec![ $( (
                stringify!($handle),
                handles::$handle.index,
                fits::<$t>(PARAMS[handles::$handle.index].kind),
            ), )* ]
        }
    };
}

pub(super) use table;

/// Whether a row of `kind` holds a `T` (test support for the macro's handle list).
#[cfg(test)]
pub(super) fn fits<T: ParamType>(kind: super::Kind) -> bool {
    use super::Kind;
    let probe = T::from_bits(0).to_value();
    matches!(
        (kind, probe),
        (Kind::F32 { .. }, Value::F32(_)) | (Kind::U32 { .. } | Kind::Choice(_), Value::U32(_))
    )
}
