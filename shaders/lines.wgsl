// Unlit lines (the faint bounding box of the volume).

// `Frame` and its binding `frame` come from frame.wgsl.

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return frame.view_proj * frame.model * vec4<f32>(position, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return frame.line_colour;
}
