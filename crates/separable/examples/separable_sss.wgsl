// Separable subsurface scattering (Jimenez et al. 2015) as two WGSL compute passes, horizontal
// then vertical, with the rules of sss-separable's CPU filter (`sss_separable::screen_space`):
//
// - Footprint: a tap's offset in pixels is its offset in mm divided by the pixel's
//   `mm_per_pixel` (the world-space size of one pixel on that pixel's surface), read linearly
//   between the two nearest texels along the pass's axis (clamped to the edges).
// - Sub-pixel skip: a pixel whose kernel diameter, 2 × support / mm_per_pixel, is under
//   `min_footprint_px` pixels or over 2^24 pixels (or whose mm_per_pixel is not a positive
//   number) is not blurred: its output is its input times the pass's kernel sum.
// - Silhouettes: a texel is dropped when it shows another object id or its depth differs from
//   the centre pixel's by more than depth_threshold × support (mm). The kept weights are then
//   renormalised per channel by the weight kept; where that is not valid (a channel whose
//   weights change sign, as in SVD terms of rank >= 2, or under 1e-6 of the weight kept) the
//   dropped weight takes the centre pixel's value instead.
// - Background pixels (object id NO_OBJECT) output 0.
// - Each pass writes its result times `params.out_scale` (per channel), plus the texel of
//   `prev` when `params.accumulate` is not 0: the vertical pass of a multi-term kernel adds
//   the terms up that way, and the rank-1 kernel's vertical pass divides by R with it.
//
// The intermediate and output images are rgba32float, so the passes keep f32 precision
// between them as the CPU filter does; texels are read with textureLoad and blended in the
// shader (no sampler), so the fractions are f32 too rather than a sampler's fixed point.
// The crate `sss-gpu` runs this file through wgpu and checks it against the CPU filter.
//
// Not included: the per-pixel jitter (rotating the taps nearer the centre than a fraction of
// the support by a hashed angle, which reads them bilinearly off-axis); without it this
// matches `FilterOptions { jitter_radius: 0.0, .. }`.
//
// The kernel: paste the output of `sss kernel --format wgsl` (or of
// `sss_separable::shader::constants(.., ShaderLanguage::Wgsl)`) between the two marker lines.
// A rank-1 kernel (`preintegrated`, `svd1`, `artist`, `guided`, `gaussians1`) is one array,
// `sssKernel`, applied in both passes; its weights sum to the total diffuse reflectance R, so
// the vertical pass divides by R once: out_scale = 1 / R there, 1 in the horizontal pass (with
// `--normalize` they sum to 1, and out_scale = R, or an albedo, in the vertical pass instead).
// A multi-term kernel (`svd3`, `svd6`, `gaussians6`) has arrays sssKernelH{i} and
// sssKernelV{i} per term i: point SSS_H and SSS_V below at one term's arrays, build one
// pipeline per term, and add the terms' vertical outputs (accumulate = 1 from the second term
// on, `prev` bound to the sum so far, `dst` to another texture). `sss_separable::shader::
// wgsl_pass` does the pasting and the pointing.
//
// Bindings (group 0, the same layout for both passes):
//   0 src           the pass's input: the irradiance (horizontal pass) or the horizontal
//                   pass's output (vertical pass), linear RGB
//   1 depth         view-space distance to the surface, in mm
//   2 object_id     the translucent object per pixel, NO_OBJECT for none
//   3 mm_per_pixel  world-space size of one pixel at its surface, in mm
//   4 dst           the pass's output (rgba32float)
//   5 params        see `Params`
//   6 prev          added to the result when params.accumulate is not 0 (the sum of the
//                   previous terms' vertical passes); bind any other texture otherwise
// Dispatch ceil(width / 8) × ceil(height / 8) workgroups per pass.

// BEGIN sss kernel
// A 3-tap placeholder; replace these lines with an exported kernel.
const sssKernel: array<vec4<f32>, 3> = array<vec4<f32>, 3>(
    vec4<f32>(0.5, 0.5, 0.5, 0.0),
    vec4<f32>(0.25, 0.25, 0.25, -1.0),
    vec4<f32>(0.25, 0.25, 0.25, 1.0)
);
const sssKernelTaps: u32 = 3u;
// END sss kernel

// The taps of the horizontal and the vertical pass: the same rank-1 array, or one term's
// sssKernelH{i} and sssKernelV{i} (and their tap counts sssKernelH{i}Taps, sssKernelV{i}Taps).
// The array types make validation fail if a tap count disagrees with its array.
const SSS_H_TAPS = sssKernelTaps;
const SSS_H: array<vec4<f32>, SSS_H_TAPS> = sssKernel;
const SSS_V_TAPS = sssKernelTaps;
const SSS_V: array<vec4<f32>, SSS_V_TAPS> = sssKernel;

const NO_OBJECT: u32 = 0xffffffffu;

struct Params {
    // The kernel's support in mm (`SeparableKernel::support_mm`, at least the largest tap
    // offset): it sets the sub-pixel skip and the depth threshold.
    support_mm: f32,
    // A texel is dropped when |depth - centre depth| > depth_threshold × support_mm (CPU
    // default 1).
    depth_threshold: f32,
    // Pixels whose kernel diameter is under this many pixels skip the blur (CPU default 1).
    min_footprint_px: f32,
    // Not 0: add `prev` to the result.
    accumulate: u32,
    // The result is multiplied by out_scale.rgb (w unused).
    out_scale: vec4<f32>,
}

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var depth: texture_2d<f32>;
@group(0) @binding(2) var object_id: texture_2d<u32>;
@group(0) @binding(3) var mm_per_pixel: texture_2d<f32>;
@group(0) @binding(4) var dst: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var<uniform> params: Params;
@group(0) @binding(6) var prev: texture_2d<f32>;

// One pixel of one pass: its inputs and the running sums over the taps.
struct Pass {
    pixel: vec2<i32>,
    // (1, 0) for the horizontal pass, (0, 1) for the vertical one.
    axis: vec2<i32>,
    // The last texel index along the axis.
    last: i32,
    id: u32,
    depth: f32,
    // depth_threshold × support (mm).
    depth_mm: f32,
    // Pixels per mm; 0 when the pixel skips the blur.
    inv_scale: f32,
    centre: vec3<f32>,
    // Σ weight × texel over the kept texels.
    acc: vec3<f32>,
    // Σ weight over the dropped texels.
    dropped: vec3<f32>,
    // Σ weight over the taps, and the smallest and largest weight, per channel.
    sum: vec3<f32>,
    wmin: vec3<f32>,
    wmax: vec3<f32>,
    any_drop: bool,
}

fn begin(pixel: vec2<i32>, axis: vec2<i32>) -> Pass {
    var s: Pass;
    s.pixel = pixel;
    s.axis = axis;
    s.last = dot(vec2<i32>(textureDimensions(src)), axis) - 1;
    s.id = textureLoad(object_id, pixel, 0).r;
    s.depth = textureLoad(depth, pixel, 0).r;
    s.depth_mm = params.depth_threshold * params.support_mm;
    s.centre = textureLoad(src, pixel, 0).rgb;
    s.acc = vec3<f32>(0.0);
    s.dropped = vec3<f32>(0.0);
    s.sum = vec3<f32>(0.0);
    s.wmin = vec3<f32>(0.0);
    s.wmax = vec3<f32>(0.0);
    s.any_drop = false;
    // Sub-pixel skip: blur only where the kernel covers at least min_footprint_px pixels,
    // and at most 2^24 (beyond, tap positions lose their fractions in f32).
    // (Background pixels read no taps either: they output 0.)
    let mmpp = textureLoad(mm_per_pixel, pixel, 0).r;
    s.inv_scale = 0.0;
    if (s.id != NO_OBJECT && mmpp > 0.0 && mmpp < 3.0e38) {
        let inv = 1.0 / mmpp;
        let span = 2.0 * params.support_mm * inv;
        if (span >= params.min_footprint_px && span <= 16777216.0 && inv < 3.0e38) {
            s.inv_scale = inv;
        }
    }
    return s;
}

// Adds texel `q` (index along the axis) with weight bw × w, or drops it.
fn add_texel(s: ptr<function, Pass>, q: i32, bw: f32, w: vec3<f32>) {
    if (bw == 0.0) {
        return;
    }
    let j = (*s).pixel + (*s).axis * (q - dot((*s).pixel, (*s).axis));
    let ww = bw * w;
    let other_object = textureLoad(object_id, j, 0).r != (*s).id;
    let depth_jump = abs(textureLoad(depth, j, 0).r - (*s).depth) > (*s).depth_mm;
    if (other_object || depth_jump) {
        (*s).any_drop = true;
        (*s).dropped += ww;
    } else {
        (*s).acc += ww * textureLoad(src, j, 0).rgb;
    }
}

// One tap vec4(r, g, b, offset_mm): a linear read at the pixel minus the offset in pixels.
fn add_tap(s: ptr<function, Pass>, tap: vec4<f32>) {
    let w = tap.rgb;
    (*s).sum += w;
    (*s).wmin = min((*s).wmin, w);
    (*s).wmax = max((*s).wmax, w);
    if ((*s).inv_scale == 0.0) {
        return;
    }
    let x = f32(dot((*s).pixel, (*s).axis));
    let p = clamp(x - tap.w * (*s).inv_scale, -1.0, f32((*s).last) + 1.0);
    let p0 = floor(p);
    let f = p - p0;
    let i0 = i32(p0);
    add_texel(s, clamp(i0, 0, (*s).last), 1.0 - f, w);
    add_texel(s, clamp(i0 + 1, 0, (*s).last), f, w);
}

fn finish(s: ptr<function, Pass>) -> vec3<f32> {
    if ((*s).id == NO_OBJECT) {
        return vec3<f32>(0.0);
    }
    if ((*s).inv_scale == 0.0) {
        return (*s).centre * (*s).sum;
    }
    if (!(*s).any_drop) {
        return (*s).acc;
    }
    let sum = (*s).sum;
    let kept = sum - (*s).dropped;
    let one_signed = ((*s).wmin >= vec3<f32>(0.0)) | ((*s).wmax <= vec3<f32>(0.0));
    let valid = one_signed & (kept * sum > vec3<f32>(0.0)) & (abs(kept) > 1e-6 * abs(sum));
    let renormalised = (*s).acc * (sum / select(vec3<f32>(1.0), kept, valid));
    let centre_filled = (*s).acc + (*s).dropped * (*s).centre;
    return select(centre_filled, renormalised, valid);
}

// Writes a pass's result: scaled, plus the previous terms' sum when accumulating.
fn store(pixel: vec2<i32>, result: vec3<f32>) {
    var v = result * params.out_scale.rgb;
    if (params.accumulate != 0u) {
        v += textureLoad(prev, pixel, 0).rgb;
    }
    textureStore(dst, pixel, vec4<f32>(v, 1.0));
}

@compute @workgroup_size(8, 8)
fn sss_horizontal(@builtin(global_invocation_id) gid: vec3<u32>) {
    let pixel = vec2<i32>(gid.xy);
    if (any(pixel >= vec2<i32>(textureDimensions(src)))) {
        return;
    }
    var s = begin(pixel, vec2<i32>(1, 0));
    for (var i = 0u; i < SSS_H_TAPS; i++) {
        add_tap(&s, SSS_H[i]);
    }
    store(pixel, finish(&s));
}

@compute @workgroup_size(8, 8)
fn sss_vertical(@builtin(global_invocation_id) gid: vec3<u32>) {
    let pixel = vec2<i32>(gid.xy);
    if (any(pixel >= vec2<i32>(textureDimensions(src)))) {
        return;
    }
    var s = begin(pixel, vec2<i32>(0, 1));
    for (var i = 0u; i < SSS_V_TAPS; i++) {
        add_tap(&s, SSS_V[i]);
    }
    store(pixel, finish(&s));
}
