//! `cargo xtask size-report`: where an image's flash goes, by crate, from the ELF's symbol
//! table. Each symbol in a text section (code and read-only data) is demangled and
//! attributed to the crate that defines it — a monomorphised generic to the crate of the
//! generic, and, when its name says so (v0 mangling, which the firmware builds use), to the
//! crate it was instantiated for as well — so a `TaskStorage::poll` of 20 KB shows as
//! embassy_executor code instantiated for flight_fw. The bytes between symbols (alignment,
//! section padding) are counted apart, so the crates and that rest add up to the text size.

use std::collections::BTreeMap;

use fw_elf::{self as elf, Class, ElfError};

/// Where a symbol's bytes are counted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Owner {
    /// The crate that defines the code or data (or a bracketed group for symbols without a
    /// crate: anonymous constants, unmangled C-ABI names).
    pub krate: String,
    /// For generic code: the first other non-std crate among its type arguments.
    pub instantiated_for: Option<String>,
}

/// Crates of the standard library: never "the crate a generic was instantiated for".
const STD_CRATES: &[&str] = &["core", "alloc", "std", "compiler_builtins"];

/// Group of read-only constants the compiler emits without a name (`.Lanon.*`, `anon.*`):
/// string literals, tables, panic locations; their crate is not recorded.
pub const ANONYMOUS: &str = "(anonymous constants)";
/// Group of unmangled names that are not compiler_builtins': vectors, interrupt handlers,
/// `#[no_mangle]` hooks of the runtime crates.
pub const UNMANGLED: &str = "(unmangled symbols)";

/// The owner of one (mangled) symbol name.
pub fn owner(mangled: &str) -> Owner {
    let unowned = |krate: &str| Owner {
        krate: krate.to_string(),
        instantiated_for: None,
    };
    if let Some(local) = mangled.strip_prefix(".L") {
        // A local constant named after its function (`.Lswitch.table.<name>.3`) is that
        // function's; the others (`.Lanon.*`) say nothing.
        return match local.find("_ZN").or_else(|| local.find("_R")) {
            Some(at) => owner(local_name(local.get(at..).unwrap_or_default())),
            None => unowned(ANONYMOUS),
        };
    }
    if mangled.starts_with("anon.") {
        return unowned(ANONYMOUS);
    }
    let Ok(demangled) = rustc_demangle::try_demangle(mangled) else {
        return unowned(if is_builtin(mangled) {
            "compiler_builtins"
        } else {
            UNMANGLED
        });
    };
    let name = format!("{demangled:#}");
    let krate = defining_crate(&name);
    // v0 names say which crate made the instance; legacy names only show the type
    // arguments, of which the first crate outside the standard library stands in.
    let instantiated_for = instantiating_crate(mangled)
        .or_else(|| {
            crates_in(&generic_args(&name))
                .into_iter()
                .find(|c| *c != krate && !STD_CRATES.contains(c))
                .map(str::to_string)
        })
        .filter(|c| c != krate);
    Owner {
        krate: krate.to_string(),
        instantiated_for,
    }
}

/// The crate a v0 name (`_R…`) says instantiated it: the optional crate root after its
/// path, spelled out (`C<disambiguator><name>`) or as a back-reference (`B<offset>_`) to one
/// earlier in the name. None for a legacy name or one without it (not generic).
fn instantiating_crate(mangled: &str) -> Option<String> {
    // A v0 name has no `.`: what follows one is a local copy's or LLVM's suffix.
    let body = mangled.strip_prefix("_R")?.split('.').next()?;
    if let Some(reference) = body.strip_suffix('_')
        && let Some(at) = reference.rfind('B')
    {
        let offset = base62(reference.get(at + 1..)?)?;
        if let Some((name, _)) = crate_root(body.get(offset..)?) {
            return Some(name.to_string());
        }
    }
    // Spelled out: the last `C` from which a crate root runs exactly to the end.
    body.char_indices()
        .rev()
        .filter(|&(_, c)| c == 'C')
        .find_map(|(i, _)| match crate_root(body.get(i..)?) {
            Some((name, "")) => Some(name.to_string()),
            _ => None,
        })
}

/// A v0 crate root at the start of `s`, `C[s<base62>_]<length>[_]<name>`: its name and
/// what follows.
fn crate_root(s: &str) -> Option<(&str, &str)> {
    let mut rest = s.strip_prefix('C')?;
    if let Some(disambiguated) = rest.strip_prefix('s') {
        let end = disambiguated.find('_')?;
        base62(disambiguated.get(..end)?)?;
        rest = disambiguated.get(end + 1..)?;
    }
    let digits = rest
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(rest.len());
    let len: usize = rest.get(..digits)?.parse().ok()?;
    let rest = rest.get(digits..)?;
    let rest = rest.strip_prefix('_').unwrap_or(rest);
    let name = rest.get(..len)?;
    name.chars()
        .all(|c| c.is_ascii_alphanumeric() || c == '_')
        .then_some((name, rest.get(len..)?))
}

/// A v0 base-62 number as it stands before its `_` (empty is 0, `n` is n + 1).
fn base62(s: &str) -> Option<usize> {
    if s.is_empty() {
        return Some(0);
    }
    let mut v = 0usize;
    for c in s.chars() {
        let d = match c {
            '0'..='9' => c as usize - '0' as usize,
            'a'..='z' => c as usize - 'a' as usize + 10,
            'A'..='Z' => c as usize - 'A' as usize + 36,
            _ => return None,
        };
        v = v.checked_mul(62)?.checked_add(d)?;
    }
    v.checked_add(1)
}

/// A mangled name with the `.N` suffix a local copy adds taken off.
fn local_name(name: &str) -> &str {
    match name.rsplit_once('.') {
        Some((base, n)) if !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()) => base,
        _ => name,
    }
}

/// compiler_builtins' exported names: the ARM EABI helpers and the C memory functions.
fn is_builtin(name: &str) -> bool {
    name.starts_with("__aeabi_")
        || matches!(name, "memcpy" | "memmove" | "memset" | "memcmp" | "bcmp")
        || (name.starts_with("__") && name.ends_with(|c: char| c.is_ascii_digit()))
}

/// The crate a demangled path belongs to: its first segment; for `<T as Trait>::f` the
/// crate of `T` (an impl lives with its type unless the type is the standard library's or
/// a primitive, then with its trait); for `<T>::f` (an inherent impl) the crate of `T`.
fn defining_crate(name: &str) -> &str {
    let Some(inner) = name.strip_prefix('<') else {
        return first_segment(name);
    };
    let inner = inner.get(..matching_close(inner)).unwrap_or(inner);
    match split_top_level(inner, " as ") {
        Some((ty, tr)) => {
            let ty_crate = path_crate(ty);
            match ty_crate {
                Some(c) if !STD_CRATES.contains(&c) => c,
                _ => path_crate(tr).or(ty_crate).unwrap_or("core"),
            }
        }
        None => path_crate(inner).unwrap_or("core"),
    }
}

/// The crate of a type or trait path (`&mut heapless::Vec<u8, 4>` → heapless); None for a
/// primitive, a tuple, an array, a slice or a function pointer.
fn path_crate(ty: &str) -> Option<&str> {
    let ty = ty
        .trim()
        .trim_start_matches('&')
        .trim_start_matches("mut ")
        .trim_start_matches("dyn ")
        .trim_start_matches("*const ")
        .trim_start_matches("*mut ");
    if ty.starts_with('<') {
        return Some(defining_crate(ty));
    }
    let path = ty.starts_with(|c: char| c.is_alphabetic() || c == '_') && ty.contains("::");
    path.then(|| first_segment(ty))
}

fn first_segment(path: &str) -> &str {
    let end = path.find(|c: char| !(c.is_alphanumeric() || c == '_'));
    path.get(..end.unwrap_or(path.len())).unwrap_or(path)
}

/// The index of the `>` that closes a `<` just before `s`.
fn matching_close(s: &str) -> usize {
    let mut depth = 0usize;
    for (i, c) in s.char_indices() {
        match c {
            '<' | '(' | '[' => depth += 1,
            '>' | ')' | ']' if depth == 0 => return i,
            '>' | ')' | ']' => depth -= 1,
            _ => {}
        }
    }
    s.len()
}

/// Splits `s` at the first `sep` outside any brackets.
fn split_top_level<'a>(s: &'a str, sep: &str) -> Option<(&'a str, &'a str)> {
    let mut depth = 0usize;
    for (i, c) in s.char_indices() {
        match c {
            '<' | '(' | '[' => depth += 1,
            '>' | ')' | ']' => depth = depth.saturating_sub(1),
            _ if depth == 0 && s.get(i..).is_some_and(|rest| rest.starts_with(sep)) => {
                return Some((s.get(..i)?, s.get(i + sep.len()..)?));
            }
            _ => {}
        }
    }
    None
}

/// Where the generic arguments of a demangled name are: past its defining path. For
/// `<T as Trait>::f` that is `T` (the trait is not a user) and what follows the brackets;
/// for `<a::T<U>>::f` and `a::f::<U>` what is inside the brackets after the path.
fn generic_args(name: &str) -> String {
    let Some(inner) = name.strip_prefix('<') else {
        return name
            .find('<')
            .and_then(|i| name.get(i..))
            .unwrap_or("")
            .to_string();
    };
    let close = matching_close(inner);
    let bracket = inner.get(..close).unwrap_or(inner);
    let after = inner.get(close + 1..).unwrap_or_default();
    let args = match split_top_level(bracket, " as ") {
        Some((ty, _)) => ty,
        None => bracket
            .find('<')
            .and_then(|i| bracket.get(i..))
            .unwrap_or(""),
    };
    format!("{args} {after}")
}

/// Crate names that start a path in `s`, in order (`a::b<c::D, e::F>` → a, c, e): the
/// identifiers followed by `::` and not preceded by it.
fn crates_in(s: &str) -> Vec<&str> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(start) = s.get(at..).and_then(|rest| rest.find(ident)) {
        let word_start = at + start;
        let tail = s.get(word_start..).unwrap_or_default();
        let len = tail.find(|c: char| !ident(c)).unwrap_or(tail.len());
        let word = tail.get(..len).unwrap_or_default();
        let before = s.get(..word_start).unwrap_or_default();
        if tail.get(len..).is_some_and(|t| t.starts_with("::"))
            && !before.ends_with("::")
            && !word.starts_with(|c: char| c.is_ascii_digit())
        {
            out.push(word);
        }
        at = word_start + len.max(1);
    }
    out
}

/// One sized symbol in the text, demangled, with its owner.
#[derive(Debug, Clone)]
pub struct Item {
    pub name: String,
    pub size: u32,
    pub owner: Owner,
}

/// An image's text by owner.
#[derive(Debug, Clone, Default)]
pub struct Breakdown {
    /// The text size (`size`'s count).
    pub text: u32,
    /// Bytes per defining crate.
    pub by_crate: BTreeMap<String, u32>,
    /// Bytes of generic code per (defining crate, crate instantiated for).
    pub by_instance: BTreeMap<(String, String), u32>,
    /// Every sized symbol in the text, largest first.
    pub items: Vec<Item>,
}

impl Breakdown {
    /// Text bytes no symbol covers (alignment and padding between them).
    pub fn between_symbols(&self) -> u32 {
        self.text
            .saturating_sub(self.by_crate.values().copied().sum::<u32>())
    }
}

/// The breakdown of one firmware ELF.
pub fn breakdown(image: &[u8]) -> Result<Breakdown, ElfError> {
    let text: Vec<_> = elf::alloc_sections(image)?
        .into_iter()
        .filter(|s| s.class == Class::Text)
        .collect();
    let in_text = |a: u32| {
        text.iter()
            .any(|s| (s.address..s.address + s.size).contains(&a))
    };
    // One entry per address (aliases such as two interrupt names on one handler), the
    // largest size kept.
    let mut by_address: BTreeMap<u32, elf::Symbol> = BTreeMap::new();
    for s in elf::symbols(image)? {
        let address = s.address & !1;
        if s.size == 0 || !in_text(address) {
            continue;
        }
        let keep = by_address.get(&address).is_none_or(|k| k.size < s.size);
        if keep {
            by_address.insert(address, s);
        }
    }
    let mut out = Breakdown {
        text: text.iter().map(|s| s.size).sum(),
        ..Breakdown::default()
    };
    for s in by_address.into_values() {
        let owner = owner(&s.name);
        *out.by_crate.entry(owner.krate.clone()).or_default() += s.size;
        if let Some(user) = &owner.instantiated_for {
            *out.by_instance
                .entry((owner.krate.clone(), user.clone()))
                .or_default() += s.size;
        }
        out.items.push(Item {
            name: demangled(&s.name),
            size: s.size,
            owner,
        });
    }
    out.items
        .sort_by(|a, b| b.size.cmp(&a.size).then_with(|| a.name.cmp(&b.name)));
    Ok(out)
}

/// A symbol's demangled name without hashes (the mangled one when it is not Rust's; a
/// local constant named after a function as `.Lswitch.table. <function>`).
pub fn demangled(mangled: &str) -> String {
    if let Some(local) = mangled.strip_prefix(".L")
        && let Some(at) = local.find("_ZN").or_else(|| local.find("_R"))
        && let Ok(d) = rustc_demangle::try_demangle(local_name(local.get(at..).unwrap_or_default()))
    {
        return format!(".L{} {d:#}", local.get(..at).unwrap_or_default());
    }
    match rustc_demangle::try_demangle(mangled) {
        Ok(d) => format!("{d:#}"),
        Err(_) => mangled.to_string(),
    }
}

/// `name` with generic arguments nested deeper than one level elided (`Join<A<…>, B>`),
/// cut to `max` characters.
pub fn short_name(name: &str, max: usize) -> String {
    let mut out = String::new();
    let mut depth = 0usize;
    for c in name.chars() {
        match c {
            // `<` opening a name (`<T as Trait>`) is not a generic argument list.
            '<' if out.is_empty() || out.ends_with(['<', ' ', '&']) => {
                out.push(c);
            }
            '<' => {
                depth += 1;
                if depth == 2 {
                    out.push_str("<…");
                } else if depth < 2 {
                    out.push(c);
                }
            }
            '>' if depth > 0 => {
                depth -= 1;
                if depth < 2 {
                    out.push(c);
                }
            }
            _ if depth >= 2 => {}
            _ => out.push(c),
        }
    }
    if out.chars().count() > max {
        let cut: String = out.chars().take(max.saturating_sub(1)).collect();
        return format!("{cut}…");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn owned(krate: &str, user: Option<&str>) -> Owner {
        Owner {
            krate: krate.into(),
            instantiated_for: user.map(Into::into),
        }
    }

    #[test]
    fn legacy_names_go_to_their_first_segment_or_their_types_crate() {
        // flight_core::control::dare::residual
        assert_eq!(
            owner("_ZN11flight_core7control4dare8residual17h48eee08e5fbee3daE"),
            owned("flight_core", None)
        );
        // <f32 as core::str::traits::FromStr>::from_str: a primitive's impl is its trait's.
        assert_eq!(
            owner(
                "_ZN50_$LT$f32$u20$as$u20$core..str..traits..FromStr$GT$8from_str17h0123456789abcdefE"
            ),
            owned("core", None)
        );
        // <embassy_futures::join::Join<Fut1,Fut2> as core::future::future::Future>::poll
        assert_eq!(
            owner(
                "_ZN95_$LT$embassy_futures..join..Join$LT$Fut1$C$Fut2$GT$$u20$as$u20$core..future..future..Future$GT$4poll17hef52c6ea88ccda53E"
            ),
            owned("embassy_futures", None)
        );
    }

    #[test]
    fn v0_generics_name_the_crate_they_were_instantiated_for() {
        // Names from the Sparky2 image (rustc 1.95, -C symbol-mangling-version=v0).
        // <embassy_executor::raw::TaskStorage<flight_fw::…::imu_task…>>::poll: the crate
        // after the path is a back-reference to flight_fw's root inside the name.
        let task = "_RNvMs1_NtCs5APViPlMGpI_16embassy_executor3rawINtB5_11TaskStorageNCNvNvNtNtNtCskS6WS2dQ9pv_9flight_fw8firmware5tasks3imu15___imu_task_task30___imu_task_task_inner_function0E4pollB1c_";
        let d = demangled(task);
        assert!(d.contains("TaskStorage") && d.contains("imu_task"), "{d}");
        assert_eq!(owner(task), owned("embassy_executor", Some("flight_fw")));
        assert_eq!(instantiating_crate(task).as_deref(), Some("flight_fw"));
        // <radio_rfm22b::rfm22b::Rfm22b<ExclusiveDevice<…>, …>>::reinit's closure, spelled
        // out at the end; its type arguments name embedded_hal_bus first, but flight_fw
        // made it.
        let reinit = "_RNCNvMs3_NtCsf1gCS7kkQdt_12radio_rfm22b6rfm22bINtB7_6Rfm22bINtNtNtCs1pz4WfBUr2T_16embedded_hal_bus3spi9exclusive15ExclusiveDeviceINtNtCs2zkBppUBX7j_13embassy_stm323spi3SpiNtNtB28_4mode5AsyncNtNtB26_4mode6MasterENtNtB28_4gpio6OutputNtB10_7NoDelayEINtNtB28_4exti9ExtiInputB2J_ENtB7_5NoPinNtNtCsf2K69dUfvf5_12embassy_time5delay5DelayE6reinit0CskS6WS2dQ9pv_9flight_fw";
        assert_eq!(owner(reinit), owned("radio_rfm22b", Some("flight_fw")));
        assert_eq!(
            owner(&format!(".Lswitch.table.{reinit}.1138")).krate,
            "radio_rfm22b"
        );
        // Not generic: no instantiating crate.
        assert_eq!(
            instantiating_crate("_RNvNtCs7ldSeZOOJos_4core3num7dec2flt"),
            None
        );
    }

    #[test]
    fn base62_and_crate_roots_follow_the_v0_grammar() {
        assert_eq!(base62(""), Some(0));
        assert_eq!(base62("0"), Some(1));
        assert_eq!(base62("1c"), Some(62 + 12 + 1));
        assert_eq!(base62("Z"), Some(62));
        assert_eq!(
            crate_root("CskS6WS2dQ9pv_9flight_fwE"),
            Some(("flight_fw", "E"))
        );
        assert_eq!(crate_root("C4core"), Some(("core", "")));
        assert_eq!(crate_root("C9short"), None);
        assert_eq!(crate_root("Nv4core"), None);
    }

    #[test]
    fn demangled_paths_are_attributed_by_their_structure() {
        assert_eq!(
            defining_crate(
                "flight_core::app::link::<impl flight_core::app::FlightApp>::next_report"
            ),
            "flight_core"
        );
        assert_eq!(
            defining_crate(
                "<radio_rfm22b::link::LinkRadio<S, I> as telemetry::link::radio::PacketRadio>::configure::{closure#0}"
            ),
            "radio_rfm22b"
        );
        assert_eq!(
            defining_crate("<&mut heapless::vec::Vec<u8, 4> as core::fmt::Debug>::fmt"),
            "heapless"
        );
        assert_eq!(
            defining_crate("<[u8] as defmt::traits::Format>::format"),
            "defmt"
        );
        assert_eq!(
            defining_crate("<core::option::Option<u8> as defmt::traits::Format>::format"),
            "defmt"
        );
        assert_eq!(defining_crate("<f32>::powf"), "core");
        assert_eq!(
            defining_crate("<embassy_executor::raw::TaskStorage<x::F>>::poll"),
            "embassy_executor"
        );
        assert_eq!(
            crates_in("core::ptr::drop_in_place::<flight_core::a::B<heapless::C>>"),
            vec!["core", "flight_core", "heapless"]
        );
    }

    #[test]
    fn a_local_table_belongs_to_its_function() {
        let join = "_ZN95_$LT$embassy_futures..join..Join$LT$Fut1$C$Fut2$GT$$u20$as$u20$core..future..future..Future$GT$4poll17hef52c6ea88ccda53E";
        for local in [
            format!(".Lswitch.table.{join}"),
            format!(".Lswitch.table.{join}.3"),
        ] {
            assert_eq!(owner(&local).krate, "embassy_futures", "{local}");
        }
    }

    #[test]
    fn symbols_without_a_crate_are_grouped() {
        assert_eq!(
            owner(".Lanon.88b94e7312261267de5bd5db2f6d1e4d.211").krate,
            ANONYMOUS
        );
        for builtin in ["__aeabi_dadd", "memcpy", "__udivmoddi4"] {
            assert_eq!(owner(builtin).krate, "compiler_builtins", "{builtin}");
        }
        for other in ["Reset", "TIM2", "_defmt_write", "__INTERRUPTS"] {
            assert_eq!(owner(other).krate, UNMANGLED, "{other}");
        }
    }

    #[test]
    fn short_names_elide_generic_arguments_below_the_first_level() {
        assert_eq!(
            short_name(
                "<embassy_futures::join::Join<a::F<x::Y>, b::G> as core::future::Future>::poll",
                80
            ),
            "<embassy_futures::join::Join<a::F<…>, b::G> as core::future::Future>::poll"
        );
        assert_eq!(
            short_name("<e::TaskStorage<f::task::{closure#0}>>::poll", 80),
            "<e::TaskStorage<f::task::{closure#0}>>::poll"
        );
        assert_eq!(short_name("abcdefgh", 5), "abcd…");
    }
}
