// Slices of the volume: opaque textured quads, unlit. The texture holds
// sRGB-encoded bytes in a plain Rgba8Unorm format, written as they are
// (the target is Rgba8Unorm too, see mesh.wgsl).

// `Frame` and its binding `frame` come from frame.wgsl.
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
