//! Ray tracing with Intel Embree 3 (the system library: Debian's `libembree-dev`), the kernels
//! Cycles and Mitsuba trace with: SIMD BVHs 4, 8 or 16 wide, AVX2 or AVX-512 picked at run
//! time. Built only where `build.rs` finds the library (`cfg(embree)`).
//!
//! Owns: the few Embree 3 declarations myriad calls (written out from `embree3/rtcore*.h`,
//! 3.13) and [`EmbreeScene`]: one triangle geometry per block of [`super::Blas`] (the
//! flattened world block directly in the top scene, each shared block as a scene of its own
//! placed by instance geometries), closest-hit and occlusion queries answering in the same
//! terms as the built-in tracer ([`RawHit`]: instance, triangle, t, barycentrics), and alpha
//! cut-outs through Embree's filter functions, which call the query's `accept` through the
//! intersect context.

use std::ffi::{c_char, c_void};
use std::ptr;

use super::Ray;
use super::hit::RawHit;
use crate::math::{Mat4, Vec3A};

type RtcDevice = *mut c_void;
type RtcScene = *mut c_void;
type RtcGeometry = *mut c_void;

const GEOMETRY_TYPE_TRIANGLE: u32 = 0;
const GEOMETRY_TYPE_INSTANCE: u32 = 121;
const BUFFER_TYPE_INDEX: u32 = 0;
const BUFFER_TYPE_VERTEX: u32 = 1;
const FORMAT_UINT3: u32 = 0x5003;
const FORMAT_FLOAT3: u32 = 0x9003;
const FORMAT_FLOAT4X4_COLUMN_MAJOR: u32 = 0x9244;
const BUILD_QUALITY_HIGH: u32 = 2;
const INVALID_ID: u32 = u32::MAX;

/// `struct RTCRay`.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

/// `struct RTCHit` (one instance level, as Debian's library is built).
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcHit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
}

/// `struct RTCRayHit`.
#[repr(C, align(16))]
struct RtcRayHit {
    ray: RtcRay,
    hit: RtcHit,
}

/// `struct RTCFilterFunctionNArguments`.
#[repr(C)]
struct FilterArgs {
    valid: *mut i32,
    geometry_user_ptr: *mut c_void,
    context: *const RtcContext,
    ray: *mut c_void,
    hit: *mut c_void,
    n: u32,
}

type FilterFn = unsafe extern "C" fn(*const FilterArgs);

type MemoryMonitor = unsafe extern "C" fn(*mut c_void, isize, bool) -> bool;

/// Counts the bytes Embree allocates (its user pointer is an `AtomicIsize`).
///
/// # Safety
/// `user` is the `AtomicIsize` the device was given, alive as long as the device.
unsafe extern "C" fn count_bytes(user: *mut c_void, bytes: isize, _post: bool) -> bool {
    // SAFETY: see the function's contract.
    unsafe {
        (*(user as *const std::sync::atomic::AtomicIsize)).fetch_add(bytes, std::sync::atomic::Ordering::Relaxed)
    };
    true
}

/// `struct RTCIntersectContext` (flags, filter, one instance level).
#[repr(C)]
struct RtcContext {
    flags: u32,
    filter: Option<FilterFn>,
    inst_id: [u32; 1],
}

/// Embree's context followed by what the filter functions need: Embree hands the context to
/// them unchanged, so the filter casts it back.
#[repr(C)]
struct IntersectContext<'a> {
    rtc: RtcContext,
    /// The query's acceptance test, (block, triangle, b1, b2) → keep the hit.
    accept: *const &'a dyn Fn(u32, u32, f32, f32) -> bool,
    /// The block of each top-scene geometry.
    blocks: &'a [u32],
}

#[link(name = "embree3")]
unsafe extern "C" {
    fn rtcNewDevice(config: *const c_char) -> RtcDevice;
    fn rtcReleaseDevice(device: RtcDevice);
    fn rtcSetDeviceMemoryMonitorFunction(device: RtcDevice, monitor: Option<MemoryMonitor>, user: *mut c_void);
    fn rtcGetDeviceError(device: RtcDevice) -> u32;
    fn rtcNewScene(device: RtcDevice) -> RtcScene;
    fn rtcReleaseScene(scene: RtcScene);
    fn rtcCommitScene(scene: RtcScene);
    fn rtcSetSceneBuildQuality(scene: RtcScene, quality: u32);
    fn rtcNewGeometry(device: RtcDevice, kind: u32) -> RtcGeometry;
    fn rtcReleaseGeometry(geometry: RtcGeometry);
    fn rtcCommitGeometry(geometry: RtcGeometry);
    fn rtcAttachGeometry(scene: RtcScene, geometry: RtcGeometry) -> u32;
    fn rtcSetSharedGeometryBuffer(
        geometry: RtcGeometry,
        kind: u32,
        slot: u32,
        format: u32,
        ptr: *const c_void,
        byte_offset: usize,
        byte_stride: usize,
        item_count: usize,
    );
    fn rtcSetGeometryInstancedScene(geometry: RtcGeometry, scene: RtcScene);
    fn rtcSetGeometryTransform(geometry: RtcGeometry, time_step: u32, format: u32, xfm: *const f32);
    fn rtcSetGeometryIntersectFilterFunction(geometry: RtcGeometry, filter: Option<FilterFn>);
    fn rtcSetGeometryOccludedFilterFunction(geometry: RtcGeometry, filter: Option<FilterFn>);
    fn rtcSetGeometryUserData(geometry: RtcGeometry, ptr: *mut c_void);
    fn rtcIntersect1(scene: RtcScene, context: *mut RtcContext, rayhit: *mut RtcRayHit);
    fn rtcOccluded1(scene: RtcScene, context: *mut RtcContext, ray: *mut RtcRay);
}

/// The filter of a masked geometry: asks the query's `accept` about the candidate hit and
/// rejects it (the ray goes on) where that says so.
///
/// # Safety
/// Embree calls it with the arguments it documents, a context that is an
/// [`IntersectContext`] (every query passes one) and N = 1 (single-ray queries).
unsafe extern "C" fn filter(args: *const FilterArgs) {
    // SAFETY: see the function's contract; RTCHitN of one ray is laid out as RTCHit.
    unsafe {
        let args = &*args;
        if *args.valid == 0 {
            return;
        }
        let context = &*(args.context as *const IntersectContext);
        let hit = &*(args.hit as *const RtcHit);
        // A block's own geometry is 0 in its instanced scene; the top scene's geometry id
        // (or the instance's) says which block.
        let top = if hit.inst_id[0] != INVALID_ID { hit.inst_id[0] } else { hit.geom_id };
        let block = context.blocks[top as usize];
        if !(*context.accept)(block, hit.prim_id, hit.u, hit.v) {
            *args.valid = 0;
        }
    }
}

/// What [`EmbreeScene::build`] is given of one block.
pub struct BlockTriangles<'a> {
    /// Its triangles' corners, three per triangle (16-byte `Vec3A`s, as Embree reads them).
    pub corners: &'a [Vec3A],
    /// Whether some triangle needs the acceptance test (alpha cut-outs).
    pub masked: bool,
}

/// An Embree device and the scene of every block and placement.
pub struct EmbreeScene {
    device: RtcDevice,
    top: RtcScene,
    /// Scenes of the shared blocks, released with the top one.
    blocks: Vec<RtcScene>,
    /// The block and the instance (placement) of each top-scene geometry id.
    geometry_block: Vec<u32>,
    geometry_instance: Vec<u32>,
    /// Index buffer shared with Embree: 0, 1, 2, … (the corners are in triangle order).
    _indices: Vec<u32>,
    /// What Embree holds allocated, bytes.
    bytes: Box<std::sync::atomic::AtomicIsize>,
}

// SAFETY: a committed Embree scene is safe to query from any number of threads at once
// (Embree's documented contract); nothing here changes after `build`.
unsafe impl Send for EmbreeScene {}
// SAFETY: as above.
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// Embree's scene over `blocks` placed by `placements` (block, object → world): block 0
    /// is world space and its identity placement goes straight into the top scene. `None`
    /// (with the reason) when Embree cannot start.
    pub fn build(blocks: &[BlockTriangles], placements: &[(u32, Mat4)]) -> Result<Self, String> {
        let most = blocks.iter().map(|b| b.corners.len()).max().unwrap_or(0);
        let indices: Vec<u32> = (0..most as u32).collect();
        // SAFETY: every pointer handed to Embree outlives the scene: the corners are the
        // caller's BLAS storage, which `Accel` keeps with this scene; the indices are ours.
        unsafe {
            let device = rtcNewDevice(c"verbose=0".as_ptr());
            if device.is_null() {
                return Err("Embree could not start (rtcNewDevice failed)".into());
            }
            let bytes = Box::new(std::sync::atomic::AtomicIsize::new(0));
            let counter = &*bytes as *const std::sync::atomic::AtomicIsize as *mut c_void;
            rtcSetDeviceMemoryMonitorFunction(device, Some(count_bytes), counter);
            let triangles = |b: &BlockTriangles| {
                let g = rtcNewGeometry(device, GEOMETRY_TYPE_TRIANGLE);
                let count = b.corners.len() / 3;
                rtcSetSharedGeometryBuffer(
                    g,
                    BUFFER_TYPE_VERTEX,
                    0,
                    FORMAT_FLOAT3,
                    b.corners.as_ptr().cast(),
                    0,
                    std::mem::size_of::<Vec3A>(),
                    b.corners.len(),
                );
                rtcSetSharedGeometryBuffer(
                    g,
                    BUFFER_TYPE_INDEX,
                    0,
                    FORMAT_UINT3,
                    indices.as_ptr().cast(),
                    0,
                    12,
                    count,
                );
                if b.masked {
                    rtcSetGeometryIntersectFilterFunction(g, Some(filter));
                    rtcSetGeometryOccludedFilterFunction(g, Some(filter));
                }
                rtcSetGeometryUserData(g, ptr::null_mut());
                rtcCommitGeometry(g);
                g
            };
            let top = rtcNewScene(device);
            rtcSetSceneBuildQuality(top, BUILD_QUALITY_HIGH);
            let mut scenes: Vec<RtcScene> = vec![ptr::null_mut(); blocks.len()];
            let (mut geometry_block, mut geometry_instance) = (Vec::new(), Vec::new());
            for (instance, &(block, m)) in placements.iter().enumerate() {
                let b = &blocks[block as usize];
                if b.corners.is_empty() {
                    continue;
                }
                let g = if block == 0 && m == Mat4::IDENTITY {
                    triangles(b)
                } else {
                    if scenes[block as usize].is_null() {
                        let s = rtcNewScene(device);
                        rtcSetSceneBuildQuality(s, BUILD_QUALITY_HIGH);
                        let t = triangles(b);
                        rtcAttachGeometry(s, t);
                        rtcReleaseGeometry(t);
                        rtcCommitScene(s);
                        scenes[block as usize] = s;
                    }
                    let g = rtcNewGeometry(device, GEOMETRY_TYPE_INSTANCE);
                    rtcSetGeometryInstancedScene(g, scenes[block as usize]);
                    rtcSetGeometryTransform(g, 0, FORMAT_FLOAT4X4_COLUMN_MAJOR, m.to_cols_array().as_ptr());
                    rtcCommitGeometry(g);
                    g
                };
                let id = rtcAttachGeometry(top, g);
                rtcReleaseGeometry(g);
                debug_assert_eq!(id as usize, geometry_block.len(), "Embree numbers geometries in order");
                geometry_block.push(block);
                geometry_instance.push(instance as u32);
            }
            rtcCommitScene(top);
            let error = rtcGetDeviceError(device);
            if error != 0 {
                rtcReleaseScene(top);
                scenes.iter().filter(|s| !s.is_null()).for_each(|&s| rtcReleaseScene(s));
                rtcReleaseDevice(device);
                return Err(format!("Embree failed to build the scene (error {error})"));
            }
            Ok(Self {
                device,
                top,
                blocks: scenes.into_iter().filter(|s| !s.is_null()).collect(),
                geometry_block,
                geometry_instance,
                _indices: indices,
                bytes,
            })
        }
    }

    /// Bytes Embree holds for the scene (its BVHs), and the index buffer shared with it.
    pub fn memory_bytes(&self) -> usize {
        self.bytes.load(std::sync::atomic::Ordering::Relaxed).max(0) as usize + self._indices.len() * 4
    }

    fn context<'a>(&'a self, accept: &'a &'a dyn Fn(u32, u32, f32, f32) -> bool) -> IntersectContext<'a> {
        IntersectContext {
            rtc: RtcContext { flags: 0, filter: None, inst_id: [INVALID_ID] },
            accept,
            blocks: &self.geometry_block,
        }
    }

    fn ray(ray: &Ray, t_max: f32) -> RtcRay {
        RtcRay {
            org: ray.origin.to_array(),
            tnear: 0.0,
            dir: ray.dir.to_array(),
            time: 0.0,
            tfar: t_max,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }

    /// Whether Embree takes `ray` up to `t_max`: origin and direction components within its
    /// `FLT_LARGE` (1.844·10¹⁸) and a distance that is not NaN. Its kernels assert this (the
    /// Debian build aborts the process on such a ray, which a broken file's camera far
    /// outside every sane size can send); such a ray meets nothing, as in the built-in tracer.
    #[inline(always)]
    fn traceable(ray: &Ray, t_max: f32) -> bool {
        const LARGE: f32 = 1.844e18;
        let finite = ray.origin.is_finite() && ray.dir.is_finite();
        finite && ray.origin.abs().max(ray.dir.abs()).max_element() <= LARGE && t_max >= 0.0
    }

    /// The closest hit with `t ∈ (0, t_max)` that `accept(block, tri, b1, b2)` keeps.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray, t_max: f32, accept: &dyn Fn(u32, u32, f32, f32) -> bool) -> Option<RawHit> {
        if !Self::traceable(ray, t_max) {
            return None;
        }
        let mut context = self.context(&accept);
        let mut rh = RtcRayHit {
            ray: Self::ray(ray, t_max),
            hit: RtcHit { ng: [0.0; 3], u: 0.0, v: 0.0, prim_id: 0, geom_id: INVALID_ID, inst_id: [INVALID_ID] },
        };
        // SAFETY: a committed scene, a context whose head is RTCIntersectContext, a RayHit
        // laid out as Embree's.
        unsafe { rtcIntersect1(self.top, &mut context.rtc, &mut rh) };
        if rh.hit.geom_id == INVALID_ID {
            return None;
        }
        let top = if rh.hit.inst_id[0] != INVALID_ID { rh.hit.inst_id[0] } else { rh.hit.geom_id };
        Some(RawHit {
            instance: self.geometry_instance[top as usize],
            tri: rh.hit.prim_id,
            t: rh.ray.tfar,
            b1: rh.hit.u,
            b2: rh.hit.v,
        })
    }

    /// True when something `accept` keeps lies on the ray within `t ∈ (0, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32, accept: &dyn Fn(u32, u32, f32, f32) -> bool) -> bool {
        if !Self::traceable(ray, t_max) {
            return false;
        }
        let mut context = self.context(&accept);
        let mut r = Self::ray(ray, t_max);
        // SAFETY: as for `closest_hit`.
        unsafe { rtcOccluded1(self.top, &mut context.rtc, &mut r) };
        // Embree marks an occluded ray by setting tfar to −∞.
        r.tfar == f32::NEG_INFINITY
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: the handles are ours and released once.
        unsafe {
            rtcReleaseScene(self.top);
            for &s in &self.blocks {
                rtcReleaseScene(s);
            }
            rtcReleaseDevice(self.device);
        }
    }
}
