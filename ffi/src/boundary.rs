//! The panic boundary every exported function runs inside, the thread-local last-error message,
//! and the checks that turn raw C arguments (pointers, lengths, strings) into Rust values or a
//! status. Owns nothing else: no handles (`handles.rs`), no rendering.

use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::status::ShikkiStatus;

/// A failed call: the status C sees and the message `shikki_last_error` returns.
#[derive(Debug)]
pub struct FfiError {
    pub status: ShikkiStatus,
    pub message: String,
}

pub type FfiResult<T = ()> = Result<T, FfiError>;

impl FfiError {
    pub fn new(status: ShikkiStatus, message: impl Into<String>) -> Self {
        Self {
            status,
            message: message.into(),
        }
    }

    pub fn invalid(message: impl Into<String>) -> Self {
        Self::new(ShikkiStatus::InvalidArgument, message)
    }
}

impl From<shikki::Error> for FfiError {
    fn from(error: shikki::Error) -> Self {
        let status = match &error {
            shikki::Error::InvalidParameter { .. } => ShikkiStatus::InvalidArgument,
            shikki::Error::Parse { .. } => ShikkiStatus::ParseError,
            // A file read whole whose content is wrong at no particular line (an empty OBJ, a
            // truncated GLB, invalid glTF): malformed input, as the header says, not an I/O
            // failure.
            shikki::Error::Read { source, .. }
                if source.kind() == std::io::ErrorKind::InvalidData =>
            {
                ShikkiStatus::ParseError
            }
            shikki::Error::Read { .. }
            | shikki::Error::ReadNamedAt { .. }
            | shikki::Error::Write { .. } => ShikkiStatus::IoError,
            shikki::Error::Gpu(_) => ShikkiStatus::GpuError,
            shikki::Error::Internal(_) => ShikkiStatus::Internal,
        };
        Self::new(status, error.to_string())
    }
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

/// The message of the last failed call on this thread ("" after a successful one).
pub fn last_error_ptr() -> *const c_char {
    // `try_with`, not `with`: a C thread may call in from its own thread-exit destructors after
    // this thread's Rust thread-locals are gone, and `with` would then panic across `extern "C"`
    // (an abort). There is no message to give then, so "".
    LAST_ERROR
        .try_with(|cell| cell.borrow().as_ptr())
        .unwrap_or_else(|_| c"".as_ptr())
}

fn set_last_error(message: &str) {
    // Interior NULs would cut the C string short; they cannot come from our own messages but a
    // caller's path or TOML text may be quoted in one.
    let text = CString::new(message.replace('\0', "\\0")).unwrap_or_default();
    // Ignored during thread teardown (see `last_error_ptr`): the status still tells the caller.
    let _ = LAST_ERROR.try_with(|cell| *cell.borrow_mut() = text);
}

/// Runs `body` with unwinding caught: Ok → `SHIKKI_STATUS_OK` and an empty last error; Err →
/// its status and message; a panic → `SHIKKI_STATUS_PANIC` and the panic text. Nothing unwinds
/// into C. The last error is set when the body is done, so a call the body made back into the
/// library (a warning callback's) cannot leave its own message behind.
pub fn run(body: impl FnOnce() -> FfiResult) -> ShikkiStatus {
    let outcome = catch_unwind(AssertUnwindSafe(body)).unwrap_or_else(|payload| {
        let text = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".to_string());
        Err(FfiError::new(
            ShikkiStatus::Panic,
            format!("internal error (a bug in shikki; please report it): {text}"),
        ))
    });
    match outcome {
        Ok(()) => {
            set_last_error("");
            ShikkiStatus::Ok
        }
        Err(error) => {
            let message = if error.message.is_empty() {
                format!("{:?}", error.status)
            } else {
                error.message
            };
            set_last_error(&message);
            error.status
        }
    }
}

/// Wraps an exported function's body: `ffi_boundary!({ ...; Ok(()) })`.
macro_rules! ffi_boundary {
    ($body:block) => {
        $crate::boundary::run(move || -> $crate::boundary::FfiResult { $body })
    };
}
pub(crate) use ffi_boundary;

fn null(name: &str) -> FfiError {
    FfiError::new(
        ShikkiStatus::NullArgument,
        format!("`{name}` is NULL; pass a valid pointer"),
    )
}

/// A NUL-terminated UTF-8 string argument.
///
/// # Safety
/// `ptr` is NULL or points to a NUL-terminated string that outlives the call.
pub unsafe fn c_str<'a>(ptr: *const c_char, name: &str) -> FfiResult<&'a str> {
    if ptr.is_null() {
        return Err(null(name));
    }
    // SAFETY: non-NULL and NUL-terminated by the caller's contract.
    let text = unsafe { CStr::from_ptr(ptr) };
    text.to_str().map_err(|e| {
        FfiError::invalid(format!(
            "`{name}` is not valid UTF-8 ({e}); pass UTF-8 text"
        ))
    })
}

/// An optional string argument: NULL → None.
///
/// # Safety
/// As [`c_str`].
pub unsafe fn opt_c_str<'a>(ptr: *const c_char, name: &str) -> FfiResult<Option<&'a str>> {
    if ptr.is_null() {
        Ok(None)
    } else {
        // SAFETY: forwarded contract.
        unsafe { c_str(ptr, name) }.map(Some)
    }
}

/// Writes `value` through an out-pointer.
///
/// # Safety
/// `ptr` is NULL or valid for one write of `T`.
pub unsafe fn write_out<T>(ptr: *mut T, name: &str, value: T) -> FfiResult {
    if ptr.is_null() {
        return Err(null(name));
    }
    // SAFETY: non-NULL and writable by the caller's contract; `T: Copy`-like handle values,
    // so no previous value needs dropping.
    unsafe { ptr.write(value) };
    Ok(())
}

/// Checks an out-pointer before any work is done, so a NULL one fails fast.
pub fn check_out<T>(ptr: *mut T, name: &str) -> FfiResult {
    if ptr.is_null() {
        Err(null(name))
    } else {
        Ok(())
    }
}

/// A caller array of `len` elements.
///
/// # Safety
/// `ptr` is NULL or valid for reads of `len` elements of `T` for the duration of the call.
pub unsafe fn slice<'a, T>(ptr: *const T, len: usize, name: &str) -> FfiResult<&'a [T]> {
    if ptr.is_null() {
        return Err(null(name));
    }
    if len
        .checked_mul(std::mem::size_of::<T>())
        .map_or(true, |bytes| bytes > isize::MAX as usize)
    {
        return Err(FfiError::invalid(format!(
            "`{name}` length {len} is larger than any array can be"
        )));
    }
    // SAFETY: non-NULL, `len` elements readable by the caller's contract, size checked above.
    Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// A caller output array of `len` elements.
///
/// # Safety
/// `ptr` is NULL or valid for writes of `len` elements of `T`, not aliased during the call.
pub unsafe fn slice_mut<'a, T>(ptr: *mut T, len: usize, name: &str) -> FfiResult<&'a mut [T]> {
    if ptr.is_null() {
        return Err(null(name));
    }
    if len
        .checked_mul(std::mem::size_of::<T>())
        .map_or(true, |bytes| bytes > isize::MAX as usize)
    {
        return Err(FfiError::invalid(format!(
            "`{name}` length {len} is larger than any array can be"
        )));
    }
    // SAFETY: non-NULL, `len` elements writable and unaliased by the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr, len) })
}

/// A fixed-size array argument such as `const double transform[16]`.
///
/// # Safety
/// `ptr` is NULL or valid for reads of `N` elements.
pub unsafe fn array<T: Copy, const N: usize>(ptr: *const T, name: &str) -> FfiResult<[T; N]> {
    // SAFETY: forwarded contract.
    let items = unsafe { slice(ptr, N, name) }?;
    let mut out = [items[0]; N];
    out.copy_from_slice(items);
    Ok(out)
}

/// This thread's last error message, for the crate's tests.
#[cfg(test)]
pub(crate) fn last_error() -> String {
    // SAFETY: last_error_ptr points to this thread's NUL-terminated message.
    unsafe { CStr::from_ptr(last_error_ptr()) }
        .to_string_lossy()
        .into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_a_status_and_a_message_and_success_clears_it() {
        let status = run(|| panic!("boom"));
        assert_eq!(status, ShikkiStatus::Panic);
        assert!(last_error().contains("boom"));
        assert_eq!(run(|| Ok(())), ShikkiStatus::Ok);
        assert_eq!(last_error(), "");
    }

    #[test]
    fn null_pointers_are_reported_by_name() {
        // SAFETY: NULL is allowed by c_str's contract.
        let result = unsafe { c_str(std::ptr::null(), "path") };
        let error = result.expect_err("NULL is an error");
        assert_eq!(error.status, ShikkiStatus::NullArgument);
        assert!(error.message.contains("`path`"));
    }
}
