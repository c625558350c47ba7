//! The audited pointer helpers: the only code that dereferences a pointer
//! from the host, frees an opaque handle, or calls the host's logger.
//!
//! Each helper checks what can be checked (null, alignment, length, UTF-8,
//! the magic number of an opaque handle) and returns [`Refused`] rather
//! than touch memory that is certainly invalid. What cannot be checked
//! (that a pointer really addresses `n` live elements) is the `# Safety`
//! contract of the helper: the FMI 2.0 standard's rules for the host.

use super::instance::{FmuState, INSTANCE_MAGIC, Instance, STATE_MAGIC};
use super::types::{fmi2Byte, fmi2CallbackFunctions, fmi2Status, fmi2String};
use std::ffi::{CStr, c_void};
use std::mem::{offset_of, size_of};

/// Why a pointer argument was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refused {
    /// NULL where a value is required.
    Null,
    /// Misaligned, an impossible length, not UTF-8, or a handle without
    /// the magic number of its type.
    Invalid,
}

/// A type behind an opaque FMI handle (`fmi2Component`, `fmi2FMUstate`).
///
/// # Safety
/// The type is `#[repr(C)]` and its first field is a `u64` that holds
/// [`Tagged::MAGIC`] from construction until [`free_handle`] clears it.
pub unsafe trait Tagged: Sized {
    /// The magic number of a live value.
    const MAGIC: u64;
}

// SAFETY: Instance is #[repr(C)] with `magic: u64` first (asserted below);
// its only constructor, Instance::instantiate, sets INSTANCE_MAGIC.
unsafe impl Tagged for Instance {
    const MAGIC: u64 = INSTANCE_MAGIC;
}

// SAFETY: FmuState is #[repr(C)] with `magic: u64` first (asserted
// below); its only constructor, FmuState::new, sets STATE_MAGIC.
unsafe impl Tagged for FmuState {
    const MAGIC: u64 = STATE_MAGIC;
}

const _: () = assert!(offset_of!(Instance, magic) == 0 && offset_of!(FmuState, magic) == 0);
const _: () = assert!(INSTANCE_MAGIC != STATE_MAGIC && INSTANCE_MAGIC != 0 && STATE_MAGIC != 0);

/// Box `value` and return its opaque handle.
pub fn into_handle<T: Tagged>(value: T) -> *mut c_void {
    Box::into_raw(Box::new(value)).cast()
}

/// Null, alignment and magic-number check of a handle.
///
/// # Safety
/// `p` is null or addresses at least 8 readable bytes.
unsafe fn checked<T: Tagged>(p: *mut c_void) -> Result<*mut T, Refused> {
    if p.is_null() {
        return Err(Refused::Null);
    }
    let p = p.cast::<T>();
    if !p.is_aligned() {
        return Err(Refused::Invalid);
    }
    // SAFETY: non-null, aligned (T's alignment is at least u64's, its first
    // field) and readable by the caller's contract.
    if unsafe { p.cast::<u64>().read() } != T::MAGIC {
        return Err(Refused::Invalid);
    }
    Ok(p)
}

/// The value behind handle `p`; a null, misaligned or foreign pointer, or
/// one freed by [`free_handle`] (while its memory is not reused), is
/// refused.
///
/// # Safety
/// `p` is null, or a handle from [`into_handle`] for `T` that is not used
/// elsewhere during `'a`, or (a host error the check is there to catch)
/// addresses at least 8 readable bytes.
pub unsafe fn handle<'a, T: Tagged>(p: *mut c_void) -> Result<&'a mut T, Refused> {
    // SAFETY: by the contract, p is null or addresses 8 readable bytes.
    let p = unsafe { checked::<T>(p) }?;
    // SAFETY: the magic number says p is a live T from into_handle; no
    // other reference to it exists during 'a (the contract).
    Ok(unsafe { &mut *p })
}

/// Take back the value behind handle `p` (checked as [`handle`]) for
/// dropping, with its magic number cleared first so that a later use or
/// second free of `p` is refused while the memory is not reused.
///
/// # Safety
/// As [`handle`]; `p` is not used afterwards (the check only catches
/// violations).
pub unsafe fn free_handle<T: Tagged>(p: *mut c_void) -> Result<Box<T>, Refused> {
    // SAFETY: by the contract, p is null or addresses 8 readable bytes.
    let p = unsafe { checked::<T>(p) }?;
    // SAFETY: p is a live T from Box::into_raw in into_handle (its magic
    // number says so); its first field is the u64 magic, cleared here, and
    // the box takes the only ownership.
    unsafe {
        p.cast::<u64>().write(0);
        Ok(Box::from_raw(p))
    }
}

/// A single value the host passes by pointer, copied.
///
/// # Safety
/// `p` is null or valid for reading one `T`.
pub unsafe fn in_arg<T: Copy>(p: *const T) -> Result<T, Refused> {
    if p.is_null() {
        Err(Refused::Null)
    } else if !p.is_aligned() {
        Err(Refused::Invalid)
    } else {
        // SAFETY: non-null, aligned, readable by the contract.
        Ok(unsafe { p.read() })
    }
}

/// A single out (or in-out) argument.
///
/// # Safety
/// `p` is null or valid for reading and writing one `T`, with no other
/// reference to it during `'a`.
pub unsafe fn out_arg<'a, T>(p: *mut T) -> Result<&'a mut T, Refused> {
    if p.is_null() {
        Err(Refused::Null)
    } else if !p.is_aligned() {
        Err(Refused::Invalid)
    } else {
        // SAFETY: non-null, aligned, valid and unaliased by the contract.
        Ok(unsafe { &mut *p })
    }
}

/// A C string argument as `&str`; not UTF-8 is [`Refused::Invalid`].
///
/// # Safety
/// `p` is null or points to a NUL-terminated string that outlives `'a`.
pub unsafe fn str_arg<'a>(p: fmi2String) -> Result<&'a str, Refused> {
    if p.is_null() {
        return Err(Refused::Null);
    }
    // SAFETY: non-null and NUL-terminated by the contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| Refused::Invalid)
}

/// Null, alignment and length check of an array of `n` elements; `None`
/// for the empty array (any pointer, null included).
fn array_check<T>(p: *const T, n: usize) -> Result<Option<*const T>, Refused> {
    if n == 0 {
        Ok(None)
    } else if p.is_null() {
        Err(Refused::Null)
    } else if !p.is_aligned() || n > isize::MAX as usize / size_of::<T>().max(1) {
        Err(Refused::Invalid)
    } else {
        Ok(Some(p))
    }
}

/// A C array argument as a slice (empty for `n = 0` whatever `p` is).
///
/// # Safety
/// For `n > 0`, `p` is null or points to `n` initialized elements that are
/// not written during `'a`.
pub unsafe fn slice_arg<'a, T>(p: *const T, n: usize) -> Result<&'a [T], Refused> {
    Ok(match array_check(p, n)? {
        None => &[],
        // SAFETY: non-null, aligned, n elements of at most isize::MAX bytes
        // in all (checked), valid by the contract.
        Some(p) => unsafe { std::slice::from_raw_parts(p, n) },
    })
}

/// Like [`slice_arg`], writable.
///
/// # Safety
/// For `n > 0`, `p` is null or points to `n` writable elements with no
/// other reference to them during `'a`.
pub unsafe fn slice_arg_mut<'a, T>(p: *mut T, n: usize) -> Result<&'a mut [T], Refused> {
    Ok(match array_check(p, n)? {
        None => &mut [],
        // SAFETY: as in slice_arg; writable and unaliased by the contract.
        Some(_) => unsafe { std::slice::from_raw_parts_mut(p, n) },
    })
}

/// An `fmi2Byte` buffer (C `char`) as bytes; see [`slice_arg`].
///
/// # Safety
/// As [`slice_arg`].
pub unsafe fn bytes_arg<'a>(p: *const fmi2Byte, n: usize) -> Result<&'a [u8], Refused> {
    // SAFETY: fmi2Byte and u8 have the same size and alignment; the
    // contract is passed on.
    unsafe { slice_arg(p.cast::<u8>(), n) }
}

/// An `fmi2Byte` buffer as writable bytes; see [`slice_arg_mut`].
///
/// # Safety
/// As [`slice_arg_mut`].
pub unsafe fn bytes_arg_mut<'a>(p: *mut fmi2Byte, n: usize) -> Result<&'a mut [u8], Refused> {
    // SAFETY: as in bytes_arg.
    unsafe { slice_arg_mut(p.cast::<u8>(), n) }
}

/// Call the host's logger (when it gave one) with the format `"%s"` and
/// `message` as its one argument, so a `%` in a message is never read as
/// a conversion.
pub fn call_logger(
    callbacks: &fmi2CallbackFunctions,
    instance_name: &CStr,
    status: fmi2Status,
    category: &CStr,
    message: &CStr,
) {
    let Some(logger) = callbacks.logger else {
        return;
    };
    // SAFETY: the host gave us this logger at instantiation; every pointer
    // is a valid NUL-terminated string that outlives the call, and the
    // format "%s" consumes exactly the one string argument passed.
    unsafe {
        logger(
            callbacks.componentEnvironment,
            instance_name.as_ptr(),
            status,
            category.as_ptr(),
            c"%s".as_ptr(),
            message.as_ptr(),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_refuse_null_misaligned_and_impossible_lengths() {
        let v = [1u32, 2, 3];
        // SAFETY: every pointer below is either checked and refused before
        // use or points into `v`.
        unsafe {
            assert_eq!(slice_arg(v.as_ptr(), 3), Ok(&v[..]));
            assert_eq!(slice_arg::<u32>(std::ptr::null(), 0), Ok(&[][..]));
            assert_eq!(slice_arg::<u32>(std::ptr::null(), 1), Err(Refused::Null));
            let odd = v.as_ptr().cast::<u8>().add(1).cast::<u32>();
            assert_eq!(slice_arg(odd, 1), Err(Refused::Invalid));
            assert_eq!(slice_arg(v.as_ptr(), usize::MAX / 2), Err(Refused::Invalid));
            assert_eq!(str_arg(std::ptr::null()), Err(Refused::Null));
            assert_eq!(str_arg(c"ok".as_ptr()), Ok("ok"));
            assert_eq!(str_arg(c"\xff".as_ptr()), Err(Refused::Invalid));
        }
    }

    /// A stand-in for Instance and FmuState.
    #[repr(C)]
    struct Probe {
        magic: u64,
        payload: Vec<u8>,
    }

    // SAFETY: #[repr(C)] with the u64 magic first.
    unsafe impl Tagged for Probe {
        const MAGIC: u64 = 0x7072_6f62_6570_726f;
    }

    #[test]
    fn handles_check_their_magic_number() {
        let h = into_handle(Probe {
            magic: Probe::MAGIC,
            payload: vec![1, 2, 3],
        });
        // A zeroed buffer, larger than an instance: not ours.
        let mut foreign = vec![0u64; 1 + size_of::<Instance>() / 8];
        let f = foreign.as_mut_ptr().cast::<c_void>();
        // SAFETY: `h` is a live handle until freed; `foreign` is readable.
        unsafe {
            assert_eq!(handle::<Probe>(h).map(|p| p.payload.len()), Ok(3));
            assert_eq!(handle::<Instance>(h).err(), Some(Refused::Invalid));
            assert_eq!(handle::<FmuState>(f).err(), Some(Refused::Invalid));
            assert_eq!(handle::<Instance>(f).err(), Some(Refused::Invalid));
            let null = std::ptr::null_mut();
            assert_eq!(handle::<Instance>(null).err(), Some(Refused::Null));
            let odd = f.cast::<u8>().add(4).cast::<c_void>();
            assert_eq!(handle::<Instance>(odd).err(), Some(Refused::Invalid));
            let b = free_handle::<Probe>(h).unwrap();
            assert_eq!((b.magic, &b.payload[..]), (0, &[1, 2, 3][..]));
        }
    }
}
