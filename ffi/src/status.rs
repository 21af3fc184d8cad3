//! The status every exported function returns. The numbers are part of the ABI: never renumber,
//! only append.

/// Result of every `shikki_*` call. On anything but `SHIKKI_STATUS_OK`, `shikki_last_error()`
/// holds a message that says what was wrong and how to fix it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShikkiStatus {
    /// Success.
    Ok = 0,
    /// A required pointer argument was NULL.
    NullArgument = 1,
    /// A handle was 0, already destroyed, of another kind, or not made by this library.
    InvalidHandle = 2,
    /// A value is outside its valid range (material field, camera, image size, unknown name…).
    InvalidArgument = 3,
    /// Text input (TOML, CSV, mesh or image file) is malformed; the message names the line.
    ParseError = 4,
    /// Reading or writing a file failed.
    IoError = 5,
    /// Vulkan: no loader, no device, or a failed call.
    GpuError = 6,
    /// The caller's output buffer has the wrong size for the requested image.
    BufferSize = 7,
    /// A bug inside shikki was caught at the boundary; the object involved may be unusable.
    Panic = 8,
    /// The call needs a part of shikki this build does not have.
    Unsupported = 9,
    /// shikki reached a state its own code should have made impossible: a bug to report, not a
    /// fault of the arguments.
    Internal = 10,
}
