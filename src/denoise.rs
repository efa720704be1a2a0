//! Denoising with Intel Open Image Denoise (its "RT" filter), guided by the first-hit albedo and normal AOVs, as
//! Cycles and Blender users denoise. The library is loaded at run time, never linked: strata builds and runs
//! without it, and `--denoise` then says how to install it (`scripts/setup.sh --denoiser`, which unpacks it from
//! the PyPI wheel `pyoidn`; there is no Debian package).
use crate::output::Frame;
use anyhow::{anyhow, bail, Context as _, Result};
use std::ffi::{c_char, c_void, CStr};
use std::path::PathBuf;

/// Where `scripts/setup.sh --denoiser` puts the library.
pub const INSTALL_DIR: &str = "/opt/strata/oidn/lib";
/// The library's soname (OIDN 2).
const LIBRARY: &str = "libOpenImageDenoise.so.2";
/// Set to a path to use that library instead.
pub const LIBRARY_VARIABLE: &str = "STRATA_OIDN_LIBRARY";

// The C API (OpenImageDenoise/oidn.h, version 2): opaque handles and the few calls the RT filter needs.
type Handle = *mut c_void;
const DEVICE_TYPE_CPU: i32 = 1;
const FORMAT_FLOAT3: i32 = 3;
const ERROR_NONE: i32 = 0;

struct Api {
    new_device: unsafe extern "C" fn(i32) -> Handle,
    commit_device: unsafe extern "C" fn(Handle),
    release_device: unsafe extern "C" fn(Handle),
    device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> i32,
    new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
    #[allow(clippy::type_complexity)]
    set_shared_image: unsafe extern "C" fn(Handle, *const c_char, *mut c_void, i32, usize, usize, usize, usize, usize),
    set_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Handle),
    execute_filter: unsafe extern "C" fn(Handle),
    release_filter: unsafe extern "C" fn(Handle),
}

/// Open Image Denoise, loaded.
pub struct Denoiser {
    api: Api,
    /// Where it was loaded from (for messages).
    pub path: PathBuf,
    // Kept last: the functions above point into it.
    _library: libloading::Library,
}

impl Denoiser {
    /// Loads the library: `$STRATA_OIDN_LIBRARY`, else where `scripts/setup.sh --denoiser` installs it, else the
    /// system's. The error says how to install it.
    pub fn load() -> Result<Self> {
        let candidates: Vec<PathBuf> = match std::env::var_os(LIBRARY_VARIABLE) {
            Some(path) => vec![PathBuf::from(path)],
            None => vec![PathBuf::from(INSTALL_DIR).join(LIBRARY), PathBuf::from(LIBRARY)],
        };
        let mut tried = Vec::new();
        for path in candidates {
            // SAFETY: loading runs the library's initialisers; Open Image Denoise's only set up its own state.
            match unsafe { libloading::Library::new(&path) } {
                Ok(library) => return Self::from_library(library, path),
                Err(e) => tried.push(format!("{}: {e}", path.display())),
            }
        }
        bail!(
            "denoising needs Intel Open Image Denoise, which is not installed (tried {}); run `scripts/setup.sh \
             --denoiser` (it unpacks the library from the pyoidn wheel into {INSTALL_DIR}), or set \
             {LIBRARY_VARIABLE} to a libOpenImageDenoise.so.2",
            tried.join("; ")
        )
    }

    fn from_library(library: libloading::Library, path: PathBuf) -> Result<Self> {
        macro_rules! symbol {
            ($name:literal) => {
                // SAFETY: the types are oidn.h's for this symbol (Open Image Denoise 2).
                *unsafe { library.get($name) }
                    .with_context(|| format!("{}: no {}", path.display(), String::from_utf8_lossy($name)))?
            };
        }
        let api = Api {
            new_device: symbol!(b"oidnNewDevice"),
            commit_device: symbol!(b"oidnCommitDevice"),
            release_device: symbol!(b"oidnReleaseDevice"),
            device_error: symbol!(b"oidnGetDeviceError"),
            new_filter: symbol!(b"oidnNewFilter"),
            set_shared_image: symbol!(b"oidnSetSharedFilterImage"),
            set_bool: symbol!(b"oidnSetFilterBool"),
            commit_filter: symbol!(b"oidnCommitFilter"),
            execute_filter: symbol!(b"oidnExecuteFilter"),
            release_filter: symbol!(b"oidnReleaseFilter"),
        };
        Ok(Self { api, path, _library: library })
    }

    /// The RT filter on `colour` (linear HDR radiance), guided by `albedo` and `normal` of the same size; alpha is
    /// kept from `colour`.
    pub fn denoise(&self, colour: &Frame, albedo: &Frame, normal: &Frame) -> Result<Frame> {
        let (width, height) = (colour.width as usize, colour.height as usize);
        for (name, f) in [("albedo", albedo), ("normal", normal)] {
            if (f.width, f.height) != (colour.width, colour.height) {
                bail!("the {name} image is {}x{}, the colour {width}x{height}", f.width, f.height);
            }
        }
        let mut output = colour.clone();
        let api = &self.api;
        // SAFETY: every image outlives the filter's execution (it is released before they are dropped), each is
        // width × height RGBA f32 of which the filter reads or writes the first three floats per 16-byte pixel.
        unsafe {
            let device = (api.new_device)(DEVICE_TYPE_CPU);
            if device.is_null() {
                bail!("{}: could not create a CPU device", self.path.display());
            }
            (api.commit_device)(device);
            let result = (|| -> Result<()> {
                self.check(device, "creating the device")?;
                let filter = (api.new_filter)(device, c"RT".as_ptr());
                self.check(device, "creating the RT filter")?;
                let set = |name: &CStr, pixels: *const [f32; 4]| {
                    (api.set_shared_image)(
                        filter,
                        name.as_ptr(),
                        pixels as *mut c_void,
                        FORMAT_FLOAT3,
                        width,
                        height,
                        0,
                        16,
                        16 * width,
                    )
                };
                set(c"color", colour.pixels.as_ptr());
                set(c"albedo", albedo.pixels.as_ptr());
                set(c"normal", normal.pixels.as_ptr());
                set(c"output", output.pixels.as_mut_ptr());
                (api.set_bool)(filter, c"hdr".as_ptr(), true);
                // The guides come from raster passes: no noise in them to filter (OIDN's cleanAux).
                (api.set_bool)(filter, c"cleanAux".as_ptr(), true);
                (api.commit_filter)(filter);
                self.check(device, "committing the filter")?;
                (api.execute_filter)(filter);
                let executed = self.check(device, "denoising");
                (api.release_filter)(filter);
                executed
            })();
            (api.release_device)(device);
            result?;
        }
        if let Some(bad) = output.pixels.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(anyhow!("the denoised image has a non-finite pixel ({bad})"));
        }
        Ok(output)
    }

    /// The device's pending error, as an error naming `what`.
    fn check(&self, device: Handle, what: &str) -> Result<()> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: the device is live; the message, when set, is a C string the device owns until its next call.
        let code = unsafe { (self.api.device_error)(device, &mut message) };
        if code == ERROR_NONE {
            return Ok(());
        }
        let text = if message.is_null() {
            String::new()
        } else {
            // SAFETY: see above.
            unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
        };
        bail!("Open Image Denoise ({}), {what}: error {code}: {text}", self.path.display())
    }
}
