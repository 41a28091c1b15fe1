//! Choosing an adapter and opening a device with the features frepray can use.

use std::any::{Any, TypeId};
use std::fmt;
use std::sync::{Arc, Mutex, PoisonError};

/// Which optional features frepray may use; each can be forced off so that CI on lavapipe
/// (which has them all) also tests the paths other adapters take (GPU.md §2.2, §3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuOptions {
    /// Use `SHADER_F64` (MIS sums in f64) where the adapter has it.
    pub f64: bool,
    /// Use `SHADER_INT64` where the adapter has it.
    pub int64: bool,
    /// Use subgroup operations where the adapter has them.
    pub subgroups: bool,
    /// Keep the integrators' per-pixel sums on the GPU where the estimator allows
    /// (off: every draw is read back and added by the CPU, the first version's path).
    pub sums: bool,
    /// Compile the integrators' kernels with naga's runtime bounds checks (an index out
    /// of bounds reads zero or the last element instead of undefined memory): a
    /// diagnostic, up to 20× slower on private arrays (GPU.md §3.4). Off by default.
    pub checked: bool,
    /// The adapter to open, by its index in [`adapters`]' list (None: the first the
    /// environment allows, high-performance preferred).
    pub adapter: Option<usize>,
}

impl Default for GpuOptions {
    /// Every feature the adapter offers.
    fn default() -> Self {
        Self {
            f64: true,
            int64: true,
            subgroups: true,
            sums: true,
            checked: false,
            adapter: None,
        }
    }
}

impl GpuOptions {
    /// The defaults, with `FREPRAY_GPU_F64=off`, `FREPRAY_GPU_INT64=off`,
    /// `FREPRAY_GPU_SUBGROUPS=off` and `FREPRAY_GPU_SUMS=off` turning features off and
    /// `FREPRAY_GPU_CHECKED=on` the bounds checks on.
    pub fn from_env() -> Self {
        let var = |name: &str| std::env::var(name).ok();
        let on = |name: &str| var(name).is_none_or(|v| v != "off" && v != "0");
        Self {
            f64: on("FREPRAY_GPU_F64"),
            int64: on("FREPRAY_GPU_INT64"),
            subgroups: on("FREPRAY_GPU_SUBGROUPS"),
            sums: on("FREPRAY_GPU_SUMS"),
            checked: var("FREPRAY_GPU_CHECKED").is_some_and(|v| v == "on" || v == "1"),
            adapter: None,
        }
    }

    /// These options with `list`'s features turned off or on, and `adapter=N` (the N-th
    /// of [`adapters`], counted from 0): comma-separated
    /// `f64`, `int64`, `subgroups`, `sums` (on by default) and `checked` (off), each
    /// optionally `=on` or `=off` (a bare name turns it on), e.g. `f64=off,checked`.
    pub fn with(mut self, list: &str) -> Result<Self, GpuOptionError> {
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (name, value) = item.split_once('=').unwrap_or((item, "on"));
            if name.trim() == "adapter" {
                let i = value.trim().parse().map_err(|_| GpuOptionError::Value {
                    item: item.to_string(),
                    value: value.trim().to_string(),
                })?;
                self.adapter = Some(i);
                continue;
            }
            let value = match value.trim() {
                "on" | "1" | "true" => true,
                "off" | "0" | "false" => false,
                v => {
                    return Err(GpuOptionError::Value {
                        item: item.to_string(),
                        value: v.to_string(),
                    })
                }
            };
            let field = match name.trim() {
                "f64" => &mut self.f64,
                "int64" => &mut self.int64,
                "subgroups" => &mut self.subgroups,
                "sums" => &mut self.sums,
                "checked" => &mut self.checked,
                n => return Err(GpuOptionError::Unknown(n.to_string())),
            };
            *field = value;
        }
        Ok(self)
    }
}

/// A `--gpu-options` list that does not read ([`GpuOptions::with`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GpuOptionError {
    /// A value other than on or off.
    #[error("GPU option {item:?}: {value:?} is not on or off (adapter=: an index)")]
    Value {
        /// The list's item.
        item: String,
        /// Its value.
        value: String,
    },
    /// A name that is no option.
    #[error("GPU option {0:?}: expected f64, int64, subgroups, sums, checked or adapter=N")]
    Unknown(String),
}

/// Why no GPU could be used.
#[derive(Clone, Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter: no GPU and no software driver (install `mesa-vulkan-drivers` for
    /// lavapipe).
    #[error(
        "no GPU adapter found ({0}); on Linux without a GPU install Mesa's lavapipe \
         (apt-get install mesa-vulkan-drivers libvulkan1)"
    )]
    NoAdapter(String),
    /// `adapter=N` past the adapters there are.
    #[error("GPU adapter {asked} asked for; the adapters are: {list} (`frepray gpu list`)")]
    NoSuchAdapter {
        /// The index asked for.
        asked: usize,
        /// The adapters, `index: name`, `;`-separated ("none" without one).
        list: String,
    },
    /// The adapter refused the device.
    #[error("the GPU adapter {adapter} refused a device: {message}")]
    Device {
        /// The adapter's name.
        adapter: String,
        /// Why.
        message: String,
    },
    /// The work needs more of a limit than the device has.
    #[error("the GPU's {limit} is {have}; this needs {need}")]
    Limit {
        /// The limit's name (wgpu's).
        limit: &'static str,
        /// What the device offers.
        have: u64,
        /// What the work needs.
        need: u64,
    },
    /// A shader or pipeline failed validation, or a readback failed.
    #[error("GPU: {0}")]
    Run(String),
    /// The scene or the options use something the GPU back end does not implement
    /// yet (say what; the CPU back end renders it).
    #[error("not available on the GPU back end yet: {0} (use --backend cpu)")]
    Unsupported(String),
}

/// What the opened device is and offers.
#[derive(Clone, Debug)]
pub struct GpuInfo {
    /// Adapter name, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// Backend, e.g. Vulkan.
    pub backend: String,
    /// Discrete, integrated, CPU (software), …
    pub device_type: String,
    /// Whether f64 is in use.
    pub f64: bool,
    /// Whether int64 is in use.
    pub int64: bool,
    /// Whether subgroups are in use.
    pub subgroups: bool,
    /// Whether timestamp queries are available (stage times).
    pub timestamps: bool,
    /// Whether the integrators may keep their per-pixel sums on the GPU
    /// ([`GpuOptions::sums`]).
    pub sums: bool,
    /// The device's largest storage-buffer binding in bytes.
    pub max_storage_binding: u64,
    /// Whether the integrators' kernels run with runtime bounds checks
    /// ([`GpuOptions::checked`]).
    pub checked: bool,
}

impl fmt::Display for GpuInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({}, {}); f64 {}, int64 {}, subgroups {}, timestamps {}, sums on the GPU {}; \
             storage binding ≤ {} MiB",
            self.name,
            self.backend,
            self.device_type,
            yes(self.f64),
            yes(self.int64),
            yes(self.subgroups),
            yes(self.timestamps),
            yes(self.sums),
            self.max_storage_binding >> 20
        )?;
        if self.checked {
            write!(f, "; bounds checks on")?;
        }
        Ok(())
    }
}

/// How the feature lists of [`GpuInfo`] and [`AdapterSummary`] say whether a feature
/// is there.
fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

/// A wgpu instance as the environment allows (`WGPU_BACKEND`), and its backends.
fn instance() -> (wgpu::Instance, wgpu::Backends) {
    let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    let backends = desc.backends;
    (wgpu::Instance::new(desc), backends)
}

/// One adapter the environment offers, as `frepray gpu list` prints it: its index (what
/// `adapter=N` of [`GpuOptions::with`] names), what it is, and which of the features
/// frepray uses it has.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterSummary {
    /// Index in [`adapters`]' list.
    pub index: usize,
    /// Adapter name, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// Backend, e.g. Vulkan.
    pub backend: String,
    /// Discrete, integrated, CPU (software), …
    pub device_type: String,
    /// Whether it offers `SHADER_F64`.
    pub f64: bool,
    /// Whether it offers `SHADER_INT64`.
    pub int64: bool,
    /// Whether it offers subgroup operations.
    pub subgroups: bool,
    /// Whether it offers timestamp queries (stage times).
    pub timestamps: bool,
}

impl fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} ({}, {}); f64 {}, int64 {}, subgroups {}, timestamps {}",
            self.index,
            self.name,
            self.backend,
            self.device_type,
            yes(self.f64),
            yes(self.int64),
            yes(self.subgroups),
            yes(self.timestamps)
        )
    }
}

/// Every adapter the environment offers, in the order `adapter=N` counts them.
pub fn adapters() -> Vec<AdapterSummary> {
    let (instance, backends) = instance();
    pollster::block_on(instance.enumerate_adapters(backends))
        .iter()
        .enumerate()
        .map(|(index, a)| {
            let (i, has) = (a.get_info(), a.features());
            AdapterSummary {
                index,
                name: i.name,
                backend: format!("{:?}", i.backend),
                device_type: format!("{:?}", i.device_type),
                f64: has.contains(wgpu::Features::SHADER_F64),
                int64: has.contains(wgpu::Features::SHADER_INT64),
                subgroups: has.contains(wgpu::Features::SUBGROUP),
                timestamps: has.contains(wgpu::Features::TIMESTAMP_QUERY),
            }
        })
        .collect()
}

/// Compiled kernels kept by a [`Gpu`] for every later render, by their type and the part
/// of their source that tells them apart, and what else a render makes from the scene
/// alone and may reuse (walk grids). The module that makes them names their type (so
/// that this one names none, and depends on none of them); the type is part of the key,
/// so that what comes back is always of the type asked for.
#[derive(Default)]
pub(crate) struct KernelCache(Mutex<Vec<CachedKernels>>);

/// One entry of a [`KernelCache`]: the kernels' type, their key, the kernels once made.
type CachedKernels = (
    TypeId,
    String,
    Arc<Mutex<Option<Arc<dyn Any + Send + Sync>>>>,
);

impl KernelCache {
    /// The kernels of type `T` for `key`, made by `make` the first time they are asked
    /// for (compiling them can take minutes on llvmpipe). Others asking for the same
    /// key meanwhile wait; those asking for other keys do not (on lavapipe two
    /// compilations then use two cores). A failed `make` keeps nothing: the next asker
    /// tries again.
    pub(crate) fn get_or_make<T: Any + Send + Sync, E>(
        &self,
        key: &str,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        self.get_or_make_keeping(key, usize::MAX, make)
    }

    /// [`Self::get_or_make`], keeping at most `keep` entries of type `T`: the ones
    /// asked for last. What a scene alone determines (walk grids) changes with every
    /// edit of a model in a long session, and must not pile up.
    pub(crate) fn get_or_make_keeping<T: Any + Send + Sync, E>(
        &self,
        key: &str,
        keep: usize,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        let id = TypeId::of::<T>();
        let entry = {
            let mut cache = self.0.lock().unwrap_or_else(PoisonError::into_inner);
            match cache.iter().position(|(t, s, _)| *t == id && s == key) {
                Some(i) => {
                    // The last asked for last in the list.
                    cache[i..].rotate_left(1);
                    Arc::clone(&cache[cache.len() - 1].2)
                }
                None => {
                    let e = Arc::new(Mutex::new(None));
                    cache.push((id, key.to_string(), Arc::clone(&e)));
                    // The oldest of the type go first (one being made elsewhere lives
                    // on with its maker).
                    let mut over = cache.iter().filter(|(t, _, _)| *t == id).count();
                    cache.retain(|(t, _, _)| {
                        let drop = *t == id && over > keep;
                        over -= usize::from(drop);
                        !drop
                    });
                    e
                }
            }
        };
        let mut slot = entry.lock().unwrap_or_else(PoisonError::into_inner);
        let k = match slot.as_ref() {
            Some(k) => Arc::clone(k),
            None => {
                let k: Arc<dyn Any + Send + Sync> = Arc::new(make()?);
                *slot = Some(Arc::clone(&k));
                k
            }
        };
        Ok(k.downcast()
            .unwrap_or_else(|_| unreachable!("entries are keyed by their type")))
    }
}

/// An opened device with its queue.
pub struct Gpu {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    info: GpuInfo,
    /// The kernels compiled so far: the `direct` kernels by the scene part of their
    /// source (its expression tape), the record-terms and sums kernels; and the walk
    /// grids of the expression solids rendered so far.
    pub(crate) kernels: KernelCache,
}

impl Gpu {
    /// Opens the first adapter the environment allows (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`
    /// pin one) with the features `options` allow and the adapter has, and the adapter's
    /// own limits.
    pub fn new(options: &GpuOptions) -> Result<Gpu, GpuError> {
        let (instance, backends) = instance();
        let adapter = match options.adapter {
            None => pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                ..Default::default()
            }))
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?,
            Some(i) => {
                let mut all = pollster::block_on(instance.enumerate_adapters(backends));
                if i >= all.len() {
                    let names: Vec<String> = adapters()
                        .iter()
                        .map(|a| format!("{}: {}", a.index, a.name))
                        .collect();
                    return Err(GpuError::NoSuchAdapter {
                        asked: i,
                        list: if names.is_empty() {
                            "none".to_string()
                        } else {
                            names.join("; ")
                        },
                    });
                }
                all.swap_remove(i)
            }
        };
        let a = adapter.get_info();
        let offered = adapter.features();
        let mut want = wgpu::Features::empty();
        let mut take = |f: wgpu::Features, allowed: bool| {
            let on = allowed && offered.contains(f);
            if on {
                want |= f;
            }
            on
        };
        let f64 = take(wgpu::Features::SHADER_F64, options.f64);
        let int64 = take(wgpu::Features::SHADER_INT64, options.int64);
        let subgroups = take(wgpu::Features::SUBGROUP, options.subgroups);
        let timestamps = take(wgpu::Features::TIMESTAMP_QUERY, true);
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("frepray"),
            required_features: want,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| GpuError::Device {
            adapter: a.name.clone(),
            message: e.to_string(),
        })?;
        let info = GpuInfo {
            name: a.name,
            backend: format!("{:?}", a.backend),
            device_type: format!("{:?}", a.device_type),
            f64,
            int64,
            subgroups,
            timestamps,
            sums: options.sums,
            max_storage_binding: limits.max_storage_buffer_binding_size,
            checked: options.checked,
        };
        Ok(Gpu {
            device,
            queue,
            info,
            kernels: KernelCache::default(),
        })
    }

    /// What the device is and offers.
    pub fn info(&self) -> &GpuInfo {
        &self.info
    }

    /// An error unless a storage binding of `bytes` fits the device.
    pub fn check_binding(&self, bytes: u64) -> Result<(), GpuError> {
        let have = self.info.max_storage_binding;
        if bytes > have {
            return Err(GpuError::Limit {
                limit: "max_storage_buffer_binding_size",
                have,
                need: bytes,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::KernelCache;
    use std::sync::mpsc;
    use std::sync::Arc;
    use std::time::Duration;

    #[test]
    fn entries_are_made_once_per_type_and_key_and_failures_are_not_kept() {
        let c = KernelCache::default();
        let a = c.get_or_make::<u32, ()>("k", || Ok(1)).unwrap();
        let b = c.get_or_make::<u32, ()>("k", || Ok(2)).unwrap();
        assert!(Arc::ptr_eq(&a, &b) && *b == 1);
        // Another type under the same key is another entry.
        assert_eq!(*c.get_or_make::<u64, ()>("k", || Ok(3)).unwrap(), 3);
        assert_eq!(c.get_or_make::<u8, &str>("f", || Err("no")), Err("no"));
        assert_eq!(*c.get_or_make::<u8, &str>("f", || Ok(4)).unwrap(), 4);
    }

    #[test]
    fn entries_past_the_kept_number_go_oldest_first() {
        let c = KernelCache::default();
        let get = |k: &str, v: u32| *c.get_or_make_keeping::<u32, ()>(k, 2, || Ok(v)).unwrap();
        assert_eq!(*c.get_or_make::<u64, ()>("a", || Ok(9)).unwrap(), 9);
        assert_eq!((get("a", 1), get("b", 2)), (1, 2));
        // "a" asked for again: "b" is now the oldest, and "c" pushes it out.
        assert_eq!((get("a", 0), get("c", 3)), (1, 3));
        assert_eq!((get("a", 0), get("c", 0), get("b", 4)), (1, 3, 4));
        // "a", the oldest when "b" came back, is gone; another type under its key stays.
        assert_eq!(get("a", 5), 5);
        assert_eq!(*c.get_or_make::<u64, ()>("a", || Ok(0)).unwrap(), 9);
    }

    /// A slow make (a compilation) holds up only those asking for its key: here the
    /// make of "a" waits until another thread's make of "b" has run, which a cache
    /// locked while making would never let happen.
    #[test]
    fn makes_of_different_keys_run_at_once() {
        let c = Arc::new(KernelCache::default());
        let (tx, rx) = mpsc::channel();
        let c2 = Arc::clone(&c);
        let waiter = std::thread::spawn(move || {
            c2.get_or_make::<u32, ()>("a", || {
                // Within the make of "a": the other thread's make must get through.
                rx.recv_timeout(Duration::from_secs(20))
                    .expect("the make of \"b\" waited for the make of \"a\"");
                Ok(1)
            })
            .map(|k| *k)
        });
        // Wait until "a" is being made (its entry exists and is locked).
        loop {
            let entries = c.0.lock().unwrap();
            if entries
                .iter()
                .any(|(_, s, e)| s == "a" && e.try_lock().is_err())
            {
                break;
            }
            drop(entries);
            std::thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(*c.get_or_make::<u32, ()>("b", || Ok(2)).unwrap(), 2);
        tx.send(()).unwrap();
        assert_eq!(waiter.join().unwrap(), Ok(1));
    }
}
