//! The conventions every export shares: the status, the thread's last
//! error message, the panic boundary, NULL and size checks.

use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The outcome of a fallible call. Outputs are written only on `OFMPC_OK`;
/// otherwise [`ofmpc_last_error`] says what and where.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ofmpc_status {
    /// Success.
    OFMPC_OK = 0,
    /// A required pointer was NULL.
    OFMPC_NULL_ARG = 1,
    /// An argument is out of its range (a kind name, a non-finite value, …).
    OFMPC_INVALID_ARG = 2,
    /// An array has the wrong length, or a record's `size` is too small.
    OFMPC_SIZE_MISMATCH = 3,
    /// The object cannot work as configured (the library refused to build it).
    OFMPC_BUILD = 4,
    /// A text (TOML, URDF, G-code) could not be read: the message says where.
    OFMPC_PARSE = 5,
    /// A numerical failure the call cannot recover from.
    OFMPC_NUMERIC = 6,
    /// A controller was stepped before it was reset.
    OFMPC_NOT_RESET = 7,
    /// The run or the plan has no more samples.
    OFMPC_END = 8,
    /// A text is not valid UTF-8.
    OFMPC_UTF8 = 9,
    /// A bug: the library panicked (the panic was caught at the boundary).
    OFMPC_PANIC = 100,
}

/// A failed call: its status and message.
#[derive(Debug)]
pub(crate) struct Failure {
    pub status: ofmpc_status,
    pub message: String,
}

impl Failure {
    pub fn new(status: ofmpc_status, message: impl Into<String>) -> Self {
        Self {
            status,
            message: message.into(),
        }
    }
}

pub(crate) type Res = Result<(), Failure>;

thread_local! {
    static LAST_ERROR: RefCell<Option<CString>> = const { RefCell::new(None) };
}

/// Stores `message` as the thread's last error (NUL bytes replaced).
fn set_last_error(message: &str) {
    let text = CString::new(message.replace('\0', "\u{FFFD}")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = Some(text));
}

/// Runs one export's body: `OFMPC_OK` on success; on failure or panic the
/// status, with the message stored for [`ofmpc_last_error`]. Allocates
/// nothing on success.
pub(crate) fn boundary(body: impl FnOnce() -> Res) -> ofmpc_status {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => ofmpc_status::OFMPC_OK,
        Ok(Err(f)) => {
            set_last_error(&f.message);
            f.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            set_last_error(&format!(
                "internal error (a bug in ofmpc, please report it): {what}"
            ));
            ofmpc_status::OFMPC_PANIC
        }
    }
}

/// A value-returning query inside the panic boundary: `fallback` on a NULL
/// handle or a panic.
pub(crate) fn query<T: Copy>(fallback: T, body: impl FnOnce() -> Option<T>) -> T {
    catch_unwind(AssertUnwindSafe(body))
        .ok()
        .flatten()
        .unwrap_or(fallback)
}

/// `p` as a reference, or `OFMPC_NULL_ARG` naming `what`.
pub(crate) unsafe fn arg<'a, T>(p: *const T, what: &str) -> Result<&'a T, Failure> {
    // SAFETY: the caller passes NULL or a valid pointer (header contract).
    unsafe { p.as_ref() }.ok_or_else(|| null(what))
}

/// `p` as a mutable reference, or `OFMPC_NULL_ARG` naming `what`.
pub(crate) unsafe fn arg_mut<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Failure> {
    // SAFETY: the caller passes NULL or a valid, unaliased pointer.
    unsafe { p.as_mut() }.ok_or_else(|| null(what))
}

/// The NULL-argument failure for `what`.
pub(crate) fn null(what: &str) -> Failure {
    Failure::new(ofmpc_status::OFMPC_NULL_ARG, format!("{what} is NULL"))
}

/// A NUL-terminated UTF-8 text argument.
pub(crate) unsafe fn text<'a>(p: *const c_char, what: &str) -> Result<&'a str, Failure> {
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: non-NULL and NUL-terminated (header contract).
    unsafe { CStr::from_ptr(p) }.to_str().map_err(|e| {
        Failure::new(
            ofmpc_status::OFMPC_UTF8,
            format!(
                "{what} is not UTF-8 (byte {}): pass UTF-8 text",
                e.valid_up_to()
            ),
        )
    })
}

/// An optional text argument (NULL = `None`).
pub(crate) unsafe fn opt_text<'a>(
    p: *const c_char,
    what: &str,
) -> Result<Option<&'a str>, Failure> {
    if p.is_null() {
        Ok(None)
    } else {
        // SAFETY: as `text`.
        unsafe { text(p, what) }.map(Some)
    }
}

/// `len` doubles at `p`, checked against `expected`.
pub(crate) unsafe fn slice<'a>(
    p: *const f64,
    len: usize,
    expected: usize,
    what: &str,
) -> Result<&'a [f64], Failure> {
    check_len(len, expected, what)?;
    if p.is_null() {
        return if expected == 0 {
            Ok(&[])
        } else {
            Err(null(what))
        };
    }
    // SAFETY: non-NULL and valid for `len` doubles (header contract).
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// `len` writable doubles at `p`, checked against `expected`.
pub(crate) unsafe fn slice_mut<'a>(
    p: *mut f64,
    len: usize,
    expected: usize,
    what: &str,
) -> Result<&'a mut [f64], Failure> {
    check_len(len, expected, what)?;
    if p.is_null() {
        return if expected == 0 {
            Ok(&mut [])
        } else {
            Err(null(what))
        };
    }
    // SAFETY: non-NULL, valid and unaliased for `len` doubles.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// `OFMPC_SIZE_MISMATCH` unless `len == expected`.
pub(crate) fn check_len(len: usize, expected: usize, what: &str) -> Res {
    if len == expected {
        Ok(())
    } else {
        Err(size_failure(what, len, expected))
    }
}

/// The size-mismatch failure. Only on the error path: allocates then.
#[cold]
fn size_failure(what: &str, len: usize, expected: usize) -> Failure {
    Failure::new(
        ofmpc_status::OFMPC_SIZE_MISMATCH,
        format!("{what} has {len} values but {expected} are needed"),
    )
}

/// A record's leading `size` must cover at least its first version
/// (`min`, the offset just past its last version-1 field).
pub(crate) fn check_record(size: usize, min: usize, what: &str) -> Res {
    if size >= min {
        Ok(())
    } else {
        Err(Failure::new(
            ofmpc_status::OFMPC_SIZE_MISMATCH,
            format!(
                "{what}.size is {size} but at least {min} bytes are needed: set it to sizeof({what})"
            ),
        ))
    }
}

/// Moves `value` to the heap and writes the handle to `out`.
pub(crate) unsafe fn give<T>(out: *mut *mut T, value: T) {
    // SAFETY: `out` was checked non-NULL by the caller.
    unsafe { *out = Box::into_raw(Box::new(value)) };
}

/// Frees a handle made by [`give`] (NULL: nothing).
pub(crate) unsafe fn take<T>(p: *mut T) {
    if !p.is_null() {
        // SAFETY: made by `Box::into_raw` in `give`, freed once (contract).
        drop(unsafe { Box::from_raw(p) });
    }
}

/// The message of the last failed call on this thread ("" if none): valid
/// until the next failing call on this thread. Never NULL.
#[no_mangle]
pub extern "C" fn ofmpc_last_error() -> *const c_char {
    query(c"".as_ptr(), || {
        Some(LAST_ERROR.with(|e| e.borrow().as_deref().unwrap_or(c"").as_ptr()))
    })
}

/// Copies the last error message (NUL-terminated, truncated to fit) into
/// `buf` of `len` bytes; returns the length the whole message needs,
/// including its NUL.
#[no_mangle]
pub unsafe extern "C" fn ofmpc_last_error_message(buf: *mut c_char, len: usize) -> usize {
    query(0, || {
        LAST_ERROR.with(|e| {
            let e = e.borrow();
            let bytes = e.as_deref().unwrap_or(c"").to_bytes_with_nul();
            if !buf.is_null() && len > 0 {
                let n = bytes.len().min(len) - 1;
                // SAFETY: `buf` holds `len` bytes (contract), n < len.
                unsafe {
                    std::ptr::copy_nonoverlapping(bytes.as_ptr().cast(), buf, n);
                    *buf.add(n) = 0;
                }
            }
            Some(bytes.len())
        })
    })
}

/// A short name of `status` ("OFMPC_OK", …); never NULL.
#[no_mangle]
pub extern "C" fn ofmpc_status_name(status: ofmpc_status) -> *const c_char {
    use ofmpc_status::*;
    let s = match status {
        OFMPC_OK => c"OFMPC_OK",
        OFMPC_NULL_ARG => c"OFMPC_NULL_ARG",
        OFMPC_INVALID_ARG => c"OFMPC_INVALID_ARG",
        OFMPC_SIZE_MISMATCH => c"OFMPC_SIZE_MISMATCH",
        OFMPC_BUILD => c"OFMPC_BUILD",
        OFMPC_PARSE => c"OFMPC_PARSE",
        OFMPC_NUMERIC => c"OFMPC_NUMERIC",
        OFMPC_NOT_RESET => c"OFMPC_NOT_RESET",
        OFMPC_END => c"OFMPC_END",
        OFMPC_UTF8 => c"OFMPC_UTF8",
        OFMPC_PANIC => c"OFMPC_PANIC",
    };
    s.as_ptr()
}

/// The library's version, "MAJOR.MINOR.PATCH" (the crate's); compare with
/// the header's `OFMPC_VERSION_*` macros to catch a header/library mismatch.
#[no_mangle]
pub extern "C" fn ofmpc_version() -> *const c_char {
    const V: &CStr =
        match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
            Ok(v) => v,
            Err(_) => c"",
        };
    V.as_ptr()
}

#[cfg(test)]
thread_local! {
    static PANIC_NEXT: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Test builds only: the next [`maybe_panic`] on this thread panics.
#[cfg(test)]
pub(crate) fn panic_next() {
    PANIC_NEXT.with(|p| p.set(true));
}

/// Test builds only: panics when [`panic_next`] asked for it (called first
/// by `ofmpc_controller_step`, to test the panic boundary).
#[cfg(test)]
pub(crate) fn maybe_panic() {
    if PANIC_NEXT.with(|p| p.replace(false)) {
        panic!("deliberate test panic inside ofmpc_controller_step");
    }
}
