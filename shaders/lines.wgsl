// Unlit lines (the faint bounding box of the volume).

struct Frame {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    fill_dir: vec4<f32>,
    // sRGB, straight alpha: written as is (the target is Rgba8Unorm).
    line_colour: vec4<f32>,
    // The clipping plane in the model frame (used by mesh.wgsl).
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

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return frame.view_proj * frame.model * vec4<f32>(position, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return frame.line_colour;
}
