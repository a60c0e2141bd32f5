// The per-frame uniforms every shader reads (layout matches `FrameUniform`
// in src/render/renderer.rs); prepended to mesh.wgsl, lines.wgsl and
// slice.wgsl when they are loaded.

struct Frame {
    view_proj: mat4x4<f32>,
    // xyz: eye position (world).
    eye: vec4<f32>,
    // xyz: unit direction towards the fill light (world).
    fill_dir: vec4<f32>,
    // Bounding-box line colour, sRGB, straight alpha (used by lines.wgsl:
    // written as is, the target is Rgba8Unorm).
    line_colour: vec4<f32>,
    // The clipping plane, in the model frame: fragments with
    // dot(clip.xyz, local) > clip.w are cut away (mesh.wgsl) when
    // clip_on.x is 1.
    clip: vec4<f32>,
    clip_on: vec4<f32>,
    // The cut-away box: fragments inside [cut_lo.xyz, cut_hi.xyz] are
    // cut away when cut_lo.w is 1.
    cut_lo: vec4<f32>,
    cut_hi: vec4<f32>,
    // The placement: model frame (meshes, box, slices, clip) to world.
    model: mat4x4<f32>,
    // Its inverse transpose, for normals.
    normal_model: mat4x4<f32>,
};

struct Style {
    // Linear rgb, straight alpha.
    colour: vec4<f32>,
    // x: 1 when highlighted.
    flags: vec4<f32>,
    // xyz: world position of quantised 0.
    origin: vec4<f32>,
    // xyz: world units per quantisation step.
    scale: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;
