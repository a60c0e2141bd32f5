// Slices of the volume: opaque textured quads, unlit. The texture holds
// sRGB-encoded bytes in a plain Rgba8Unorm format, written as they are
// (the target is Rgba8Unorm too, see mesh.wgsl).

struct Frame {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    fill_dir: vec4<f32>,
    line_colour: vec4<f32>,
    clip: vec4<f32>,
    clip_on: vec4<f32>,
    cut_lo: vec4<f32>,
    cut_hi: vec4<f32>,
    // The placement: model frame (meshes, box, slices, clip) to world.
    model: mat4x4<f32>,
    // Its inverse transpose, for normals.
    normal_model: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var image: texture_2d<f32>;
@group(1) @binding(1) var image_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) uv: vec2<f32>) -> VsOut {
    var out: VsOut;
    out.clip = frame.view_proj * frame.model * vec4<f32>(position, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let c = textureSample(image, image_sampler, in.uv);
    return vec4<f32>(c.rgb, 1.0);
}
