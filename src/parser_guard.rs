//! Third-party parsers that panic on some malformed files instead of returning an error
//! (`gltf` on an out-of-range index, `bvh_anim` on a misplaced keyword, `tobj` on a material
//! colour of fewer than three numbers): their panics are caught here and become errors, without
//! the panic message on standard error.

use std::cell::Cell;
use std::sync::Once;

thread_local! {
    static GUARDED: Cell<bool> = const { Cell::new(false) };
}

static QUIET_HOOK: Once = Once::new();

/// Runs `parse`; a panic inside it becomes `Err(its message)`. Panics elsewhere, and on other
/// threads, are reported as before.
pub(crate) fn catch_parser_panic<T>(parse: impl FnOnce() -> T) -> Result<T, String> {
    QUIET_HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !GUARDED.with(Cell::get) {
                previous(info);
            }
        }));
    });
    let was = GUARDED.with(|g| g.replace(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(parse));
    GUARDED.with(|g| g.set(was));
    result.map_err(|payload| {
        payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown failure".into())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_its_message_and_values_pass_through() {
        assert_eq!(catch_parser_panic(|| 7), Ok(7));
        let v: Vec<u8> = Vec::new();
        let err = catch_parser_panic(|| v[3]).unwrap_err();
        assert!(err.contains("index out of bounds"), "{err}");
        let err = catch_parser_panic(|| -> u8 { panic!("bad keyword {}", 3) }).unwrap_err();
        assert_eq!(err, "bad keyword 3");
    }
}
