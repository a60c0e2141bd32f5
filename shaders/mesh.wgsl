// Lit triangle meshes: two-sided headlight + fill lighting.
//
// Colours arrive linear (converted on the CPU from sRGB); lighting is done in
// linear space and the result is sRGB-encoded here, because the target is a
// plain Rgba8Unorm texture that egui samples as gamma-encoded colour.

// `Frame` and its binding `frame` come from frame.wgsl.
@group(1) @binding(0) var<uniform> style: Style;

// The compact vertex (GpuVertex in src/render/geometry.rs): position
// quantised to 16 bits in the mesh's box (Unorm16x4, read as q / 65535),
// normal in the octahedral encoding (Snorm16x2).
struct VsIn {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec2<f32>,
};

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    // The position in the model frame (for the clip).
    @location(2) local: vec3<f32>,
};

// The unit vector of an octahedral encoding (Cigolle et al., JCGT 2014).
fn decode_normal(e: vec2<f32>) -> vec3<f32> {
    let f = clamp(e, vec2<f32>(-1.0), vec2<f32>(1.0));
    var n = vec3<f32>(f.x, f.y, 1.0 - abs(f.x) - abs(f.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}

@vertex
fn vs_main(in: VsIn) -> VsOut {
    var out: VsOut;
    let local = style.origin.xyz + in.position.xyz * 65535.0 * style.scale.xyz;
    let world = (frame.model * vec4<f32>(local, 1.0)).xyz;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.local = local;
    // Not normalised here: the fragment stage does (and lights a zero
    // normal as facing the viewer).
    out.normal = (frame.normal_model * vec4<f32>(decode_normal(in.normal), 0.0)).xyz;
    return out;
}

fn srgb_from_linear(c: vec3<f32>) -> vec3<f32> {
    let c0 = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    let lo = c0 * 12.92;
    let hi = 1.055 * pow(c0, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c0 <= vec3<f32>(0.0031308));
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    if frame.clip_on.x > 0.5 && dot(frame.clip.xyz, in.local) > frame.clip.w {
        discard;
    }
    if frame.cut_lo.w > 0.5 && all(in.local >= frame.cut_lo.xyz) && all(in.local <= frame.cut_hi.xyz) {
        discard;
    }
    let v = normalize(frame.eye.xyz - in.world);
    let len = length(in.normal);
    // A zero normal (degenerate input) is lit as if facing the viewer.
    let n = select(v, in.normal / len, len > 1e-12);
    let facing = dot(n, v);
    // Two-sided: light the side we see. The side the normal points away
    // from (the "inside") is drawn darker; smoothstep avoids a hard seam at
    // silhouettes where interpolated normals graze the view direction.
    let nf = select(-n, n, facing >= 0.0);
    let side = mix(0.62, 1.0, smoothstep(-0.08, 0.08, facing));

    let head = max(dot(nf, v), 0.0);
    let fill = max(dot(nf, frame.fill_dir.xyz), 0.0);
    // Headlight specular: half vector of a light at the eye is v itself.
    let spec = pow(head, 48.0);

    let base = style.colour.rgb;
    var lit = base * (0.16 + 0.70 * head + 0.28 * fill) * side + vec3<f32>(0.16) * spec * side;

    if style.flags.x > 0.5 {
        // Highlight: a warm rim where the surface turns away, and a lift.
        let rim = pow(1.0 - head, 2.0);
        lit = mix(lit * 1.15 + base * 0.08, vec3<f32>(1.0, 0.78, 0.18), 0.85 * rim);
    }
    return vec4<f32>(srgb_from_linear(lit), style.colour.a);
}
