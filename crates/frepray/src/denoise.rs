//! Denoised previews: Intel Open Image Denoise (OIDN 2, its `RT` filter on HDR input)
//! fed with an image's colour and, where it has them, its albedo and normal AOVs.
//!
//! The library is loaded when first asked for, not linked: frepray builds and runs
//! without it. It is found, in order, at `$FREPRAY_OIDN` (the path of
//! `libOpenImageDenoise.so.2`); in the `pyoidn` package (which ships the library in its
//! wheel: `pip install pyoidn`) of the virtual environment `$VIRTUAL_ENV`, of `.venv` in
//! the current folder or of the user's and the system's Python; then by the system's
//! loader (an OIDN installed system-wide).
//!
//! A denoised image is biased: for looking at, never for measuring. Callers write it to
//! a file of its own, labelled ([`LABEL`]); experiments never denoise.

use crate::Image;
use std::ffi::{c_char, c_void, CStr, CString};
use std::path::{Path, PathBuf};

/// The EXR attribute that marks an image as denoised, with what denoised it.
pub const LABEL: &str = "frepray.denoised";

/// The library file's name.
const LIBRARY: &str = "libOpenImageDenoise.so.2";

/// Why an image was not denoised.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DenoiseError {
    /// The library is nowhere it was looked for.
    #[error(
        "Intel Open Image Denoise not found (looked in: {0}); install it with \
         `pip install pyoidn` (into .venv or any Python environment), or set FREPRAY_OIDN \
         to the path of {LIBRARY}"
    )]
    NotFound(String),
    /// The library did not load, or lacks a function.
    #[error("{path}: {message}")]
    Load {
        /// The file.
        path: PathBuf,
        /// The loader's message.
        message: String,
    },
    /// OIDN reported an error.
    #[error("Open Image Denoise: {0}")]
    Oidn(String),
}

/// The places the library is looked for, in order (module docs).
pub fn candidates() -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Some(p) = std::env::var_os("FREPRAY_OIDN") {
        out.push(PathBuf::from(p));
    }
    let mut prefixes: Vec<PathBuf> = Vec::new();
    if let Some(v) = std::env::var_os("VIRTUAL_ENV") {
        prefixes.push(PathBuf::from(v));
    }
    prefixes.push(PathBuf::from(".venv"));
    if let Some(home) = std::env::var_os("HOME") {
        prefixes.push(Path::new(&home).join(".local"));
    }
    prefixes.extend(["/usr/local", "/usr"].map(PathBuf::from));
    for prefix in prefixes {
        let Ok(libs) = std::fs::read_dir(prefix.join("lib")) else {
            continue;
        };
        let mut pythons: Vec<PathBuf> = libs
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("python3"))
            })
            .collect();
        pythons.sort();
        for py in pythons {
            for site in ["site-packages", "dist-packages"] {
                let lib = py.join(site).join("pyoidn/oidn/lib").join(LIBRARY);
                if lib.is_file() {
                    out.push(lib);
                }
            }
        }
    }
    out
}

type NewDevice = unsafe extern "C" fn(i32) -> *mut c_void;
type Handle = unsafe extern "C" fn(*mut c_void);
type GetError = unsafe extern "C" fn(*mut c_void, *mut *const c_char) -> i32;
type NewFilter = unsafe extern "C" fn(*mut c_void, *const c_char) -> *mut c_void;
type SetImage = unsafe extern "C" fn(
    *mut c_void,
    *const c_char,
    *mut c_void,
    i32,
    usize,
    usize,
    usize,
    usize,
    usize,
);
type SetBool = unsafe extern "C" fn(*mut c_void, *const c_char, bool);
type SetInt = unsafe extern "C" fn(*mut c_void, *const c_char, i32);

/// OIDN's C functions frepray calls (OIDN 2's `oidn.h`).
struct Api {
    new_device: NewDevice,
    commit_device: Handle,
    release_device: Handle,
    get_error: GetError,
    new_filter: NewFilter,
    set_image: SetImage,
    set_bool: SetBool,
    set_int: SetInt,
    commit_filter: Handle,
    execute_filter: Handle,
    release_filter: Handle,
}

/// The loaded library (kept loaded for the process: it is loaded once).
pub struct Oidn {
    api: Api,
    path: PathBuf,
}

/// `OIDN_DEVICE_TYPE_CPU`, `OIDN_FORMAT_FLOAT3`, `OIDN_QUALITY_HIGH`.
const DEVICE_CPU: i32 = 1;
const FORMAT_FLOAT3: i32 = 3;
const QUALITY_HIGH: i32 = 6;

impl Oidn {
    /// Loads the library from the first of [`candidates`] that loads, else from the
    /// system loader's path.
    pub fn load() -> Result<Oidn, DenoiseError> {
        let tried = candidates();
        let mut first_error = None;
        for path in tried.iter().chain(std::iter::once(&PathBuf::from(LIBRARY))) {
            match Self::load_from(path) {
                Ok(o) => return Ok(o),
                Err(e) if path.is_file() => {
                    first_error.get_or_insert(e);
                }
                Err(_) => {}
            }
        }
        Err(first_error.unwrap_or_else(|| {
            let mut list: Vec<String> = tried.iter().map(|p| p.display().to_string()).collect();
            list.push(
                "$FREPRAY_OIDN, pyoidn in $VIRTUAL_ENV, .venv, ~/.local, /usr/local, /usr".into(),
            );
            list.push(format!("{LIBRARY} on the loader's path"));
            DenoiseError::NotFound(list.join("; "))
        }))
    }

    /// Loads the library at `path` (a bare file name: the system loader's search).
    pub fn load_from(path: &Path) -> Result<Oidn, DenoiseError> {
        let fail = |message: String| DenoiseError::Load {
            path: path.to_path_buf(),
            message,
        };
        let name = CString::new(path.as_os_str().as_encoded_bytes())
            .map_err(|_| fail("the path holds a NUL byte".into()))?;
        // SAFETY: dlopen with a NUL-terminated name; the handle is never closed, so the
        // function pointers taken from it stay valid for the process.
        let handle = unsafe { libc::dlopen(name.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
        if handle.is_null() {
            // SAFETY: dlerror returns a NUL-terminated message or null.
            let e = unsafe { libc::dlerror() };
            let message = if e.is_null() {
                "cannot load the library".to_string()
            } else {
                unsafe { CStr::from_ptr(e) }.to_string_lossy().into_owned()
            };
            return Err(fail(message));
        }
        let sym = |name: &str| -> Result<*mut c_void, DenoiseError> {
            let c = CString::new(name).expect("a symbol name");
            // SAFETY: a valid handle and a NUL-terminated symbol name.
            let p = unsafe { libc::dlsym(handle, c.as_ptr()) };
            if p.is_null() {
                Err(fail(format!(
                    "no function {name}: not Open Image Denoise 2"
                )))
            } else {
                Ok(p)
            }
        };
        // SAFETY: each symbol is OIDN 2's function of that name, whose C signature the
        // type it is cast to spells (oidn.h).
        let api = unsafe {
            Api {
                new_device: std::mem::transmute::<*mut c_void, NewDevice>(sym("oidnNewDevice")?),
                commit_device: std::mem::transmute::<*mut c_void, Handle>(sym("oidnCommitDevice")?),
                release_device: std::mem::transmute::<*mut c_void, Handle>(sym(
                    "oidnReleaseDevice",
                )?),
                get_error: std::mem::transmute::<*mut c_void, GetError>(sym("oidnGetDeviceError")?),
                new_filter: std::mem::transmute::<*mut c_void, NewFilter>(sym("oidnNewFilter")?),
                set_image: std::mem::transmute::<*mut c_void, SetImage>(sym(
                    "oidnSetSharedFilterImage",
                )?),
                set_bool: std::mem::transmute::<*mut c_void, SetBool>(sym("oidnSetFilterBool")?),
                set_int: std::mem::transmute::<*mut c_void, SetInt>(sym("oidnSetFilterInt")?),
                commit_filter: std::mem::transmute::<*mut c_void, Handle>(sym("oidnCommitFilter")?),
                execute_filter: std::mem::transmute::<*mut c_void, Handle>(sym(
                    "oidnExecuteFilter",
                )?),
                release_filter: std::mem::transmute::<*mut c_void, Handle>(sym(
                    "oidnReleaseFilter",
                )?),
            }
        };
        Ok(Oidn {
            api,
            path: path.to_path_buf(),
        })
    }

    /// Where the library was loaded from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `img`'s colour denoised (the `RT` filter, HDR, high quality), with its albedo
    /// (`albedo.R/G/B`) and normal (`normal.X/Y/Z`) channels as guides where it has
    /// them (a normal only with an albedo, as OIDN takes them): a new image of the
    /// colour alone, labelled ([`LABEL`]) and keeping `img`'s other attributes.
    pub fn denoise(&self, img: &Image) -> Result<Image, DenoiseError> {
        let (w, h) = (img.width() as usize, img.height() as usize);
        let plane = |names: [&str; 3]| -> Option<Vec<f32>> {
            let idx: Vec<usize> = names
                .iter()
                .map(|n| img.aov_index(n).map(|i| 3 + i))
                .collect::<Option<_>>()?;
            Some(
                img.data()
                    .chunks_exact(img.channels())
                    .flat_map(|p| idx.iter().map(move |&i| p[i] as f32))
                    .collect(),
            )
        };
        let mut color: Vec<f32> = plane_rgb(img);
        let mut albedo = plane(["albedo.R", "albedo.G", "albedo.B"]);
        let mut normal = albedo
            .as_ref()
            .and(plane(["normal.X", "normal.Y", "normal.Z"]));
        let mut output = vec![0f32; w * h * 3];
        let a = &self.api;
        let c = |s: &str| CString::new(s).expect("a name");
        // SAFETY: OIDN's documented call sequence on buffers of w × h × 3 f32 that
        // outlive the filter's execution (shared images are read and written in
        // place during oidnExecuteFilter only); every object made is released.
        unsafe {
            let device = (a.new_device)(DEVICE_CPU);
            if device.is_null() {
                return Err(DenoiseError::Oidn("no device".into()));
            }
            (a.commit_device)(device);
            let check = |what: &str| -> Result<(), DenoiseError> {
                let mut msg: *const c_char = std::ptr::null();
                let code = (a.get_error)(device, &mut msg);
                if code == 0 {
                    return Ok(());
                }
                let text = if msg.is_null() {
                    format!("error {code}")
                } else {
                    CStr::from_ptr(msg).to_string_lossy().into_owned()
                };
                Err(DenoiseError::Oidn(format!("{what}: {text}")))
            };
            let result = (|| {
                check("device")?;
                let filter = (a.new_filter)(device, c("RT").as_ptr());
                check("filter")?;
                let set = |name: &str, buf: &mut Vec<f32>| {
                    (a.set_image)(
                        filter,
                        c(name).as_ptr(),
                        buf.as_mut_ptr().cast(),
                        FORMAT_FLOAT3,
                        w,
                        h,
                        0,
                        0,
                        0,
                    )
                };
                set("color", &mut color);
                if let Some(b) = albedo.as_mut() {
                    set("albedo", b);
                }
                if let Some(b) = normal.as_mut() {
                    set("normal", b);
                }
                set("output", &mut output);
                (a.set_bool)(filter, c("hdr").as_ptr(), true);
                (a.set_int)(filter, c("quality").as_ptr(), QUALITY_HIGH);
                (a.commit_filter)(filter);
                let committed = check("commit");
                if committed.is_ok() {
                    (a.execute_filter)(filter);
                }
                let done = committed.and_then(|_| check("execute"));
                (a.release_filter)(filter);
                done
            })();
            (a.release_device)(device);
            result?;
        }
        let mut out = Image::new(img.width(), img.height(), &[]);
        for (k, p) in output.chunks_exact(3).enumerate() {
            let (x, y) = ((k % w) as u32, (k / w) as u32);
            let v = [0, 1, 2].map(|c| f64::from(p[c]).max(0.0));
            out.pixel_mut(x, y)[..3].copy_from_slice(&v);
        }
        for (name, value) in img.attributes() {
            out.set_attribute(name, value.as_str());
        }
        let guides = match (albedo.is_some(), normal.is_some()) {
            (true, true) => "albedo + normal",
            (true, false) => "albedo",
            _ => "none",
        };
        out.set_attribute(
            LABEL,
            format!("Intel Open Image Denoise 2, RT filter, HDR, quality high, guides: {guides}"),
        );
        Ok(out)
    }
}

/// The colour channels as interleaved f32.
fn plane_rgb(img: &Image) -> Vec<f32> {
    img.data()
        .chunks_exact(img.channels())
        .flat_map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A library that is not there is an error naming the file, not a crash.
    #[test]
    fn a_missing_library_is_an_error_naming_it() {
        let p = Path::new("/nonexistent/libOpenImageDenoise.so.2");
        match Oidn::load_from(p) {
            Err(DenoiseError::Load { path, message }) => {
                assert_eq!(path, p);
                assert!(!message.is_empty());
            }
            other => panic!("{:?}", other.err()),
        }
    }
}
