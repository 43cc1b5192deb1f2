#version 330 core
// Materials: 0 skin (back faces: the inside of the head), 1 left eye, 2 right eye, 3 teeth, 4 tongue,
// 6 lashes (cards along the lid margins, render/lashes.py); slot 5 is the gums (teeth above their gum line).
// Four variants (render/context.program's defines): none for skin, teeth and tongue; BROWS for the skin's
// triangles about the brows (their hairs, a texture fetch); EYES for the eyeballs; LASHES for the lash cards
// (llvmpipe runs every branch for every fragment, and a discard anywhere costs the whole draw its early depth
// test: each part pays only for its own code).
// The eyes are drawn procedurally: sclera, then an iris disc of the FAPU's IRISD0 and a pupil
// whose diameter follows FAPs 29/30, both centred on the eyeball's gaze axis. Lit, the iris has
// fibres, a collarette, furrows and a dark limbal ring in the eye's own frame (they turn with the
// gaze), and the wet eye mirrors each light: a tight specular on the cornea, a steeper cap than the
// eyeball (its normal), so the highlight sits on the iris and moves with the light and the view.
// The skin mixes in the lip and brow colours (untextured only) and the dark of the oral cavity;
// the teeth get their shape from tooth coordinates: gaps, rounded tips, scalloped gums; the premolars
// and molars and any tooth's inner side sit in the mouth's shadow (at three-quarter the far side's back
// teeth, lit by the key light on that side, read as a grey wall against the dark cavity); the tongue
// likewise, lit at its tip and darker back along it and toward its edges (render/details.py).
// Unlit, every part is one flat colour (the tests classify pixels by it): brows, cavity and gums
// are then pure where their weight is 1, and hair strokes and tooth gaps are left out.
uniform vec3 camera_position;
uniform bool lighting;
uniform bool albedo;              // the surface's own colour and shadow under a unit light, details kept (the UV bake)
uniform bool orthographic;
uniform vec3 view_direction;      // toward the camera, for orthographic views

uniform vec3 base_colour[6];      // skin, mouth, sclera, teeth, tongue, gums
uniform vec2 shine[6];            // specular strength, shininess
uniform vec3 lip_colour;
uniform vec3 brow_colour;
uniform vec3 cavity_colour;
uniform vec3 iris_colour;
uniform vec3 pupil_colour;
uniform vec3 lash_colour;
uniform float cornea_radius;      // mm (face/data/eyes.csv)
uniform vec2 wet;                 // the tear film's reflection: strength, shininess
uniform vec2 lash_strands;        // strand spacing and root half width, mm

uniform vec3 eye_centre[2];
uniform vec3 eye_axis[2];         // unit gaze direction
uniform float iris_radius;        // mm
uniform float pupil_radius[2];    // mm

uniform float nose_wrinkle;       // 0..1 (face/looks.py)
uniform sampler2D brow_texture;   // the brows' hairs over (along, height): render/brows.py
uniform vec4 brow_frame;          // the texture's (along, height) origin and span

uniform bool use_texture;
uniform sampler2D skin_texture;
uniform sampler2D iris_texture;   // the iris's pattern around (x) and out from the pupil (y): render/iris.py

uniform vec3 light_direction[2];  // toward the lights
uniform vec3 light_colour[2];
uniform vec3 ambient;

in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
flat in int v_material;
in vec2 v_tints;
in vec2 v_detail;
in vec2 v_nose;
in float v_neck;

out vec4 colour;

const float IRIS_SCALE = 2.0;     // render/iris.py stores the pattern over this
const float TOOTH_MM = 7.0;       // a typical tooth width, for the tip rounding
const float TIP_MM = 1.1;         // radius of a tooth's rounded corners
const float CROWN_MM = 9.5;       // crown height at the middle of a tooth (gum line above)
const float WRINKLE_MM = 4.2;     // spacing of the nose creases
const float BACK_TEETH_SHADE = 0.03; // premolars and molars: the light that reaches inside the mouth
                                      // (0.12 left the far ones a grey slab with a jagged top at three-quarter)
const float LINGUAL_SHADE = 0.3;     // a tooth's inner side (the far side's, seen across an open mouth): in its shadow
const vec2 TONGUE_SHADOW_MM = vec2(10.0, 45.0);  // behind the tongue's tip: where the mouth's shadow begins and is full
const float TONGUE_BACK_SHADE = 0.3;  // the light that reaches the tongue's back
const float TONGUE_SIDE_SHADE = 0.55; // and its edges, under the teeth
const float BROW_TINT = 0.75;        // the brow's colour on the skin between its hairs
const float BROW_STRAY_MM = 0.5;     // how far past the brow's edge its hairs reach

#ifdef LASHES
float hash(float x) { return fract(sin(x * 127.1 + 311.7) * 43758.5453); }
#endif

#ifdef EYES
vec3 eye_colour(int eye, out int slot, out vec3 wet_normal) {
    vec3 axis = eye_axis[eye];
    vec3 offset = v_position - eye_centre[eye];
    float along = dot(offset, axis);
    vec3 side = offset - along * axis;
    float across = length(side);
    slot = 2;
    wet_normal = normalize(offset);
    float limbus = iris_radius * 1.08;
    if (along > 0.0 && across < limbus) {           // the cornea, blended into the eyeball at the limbus
        float a = min(across, 0.98 * cornea_radius);
        vec3 cornea = normalize(side / max(across, 1e-5) * a + axis * sqrt(cornea_radius * cornea_radius - a * a));
        wet_normal = normalize(mix(cornea, wet_normal, smoothstep(iris_radius * 0.9, limbus, across)));
    }
    if (!lighting && !albedo) {                       // unlit: flat colours, for the pixel tests
        if (along <= 0.0 || across > iris_radius) return base_colour[2];
        return across < pupil_radius[eye] ? pupil_colour : iris_colour;
    }
    float radius = length(offset);
    if (along <= 0.0 || across > limbus) {
        // sclera: a little darker toward the corners and under the upper lid's shadow, a little pink far out
        float far_out = smoothstep(0.35, 0.9, across / radius);
        vec3 white = mix(base_colour[2], base_colour[2] * vec3(0.97, 0.86, 0.84), far_out);
        return white * (1.0 - 0.18 * far_out) * (1.0 - 0.22 * smoothstep(0.1, 0.45, offset.y / radius));
    }
    if (across < pupil_radius[eye]) return pupil_colour;
    vec3 e1 = normalize(cross(vec3(0.0, 1.0, 0.0), axis));
    vec3 e2 = cross(axis, e1);
    float theta = atan(dot(side, e2), dot(side, e1));
    float r = clamp((across - pupil_radius[eye]) / max(iris_radius - pupil_radius[eye], 1e-3), 0.0, 1.0);
    vec3 iris = iris_colour * textureLod(iris_texture, vec2(theta * 0.15915494 + 0.5, r), 0.0).rgb * IRIS_SCALE;
    if (across > iris_radius) {                     // limbal ring, blended into the sclera
        float t = (across - iris_radius) / (limbus - iris_radius);
        return mix(iris_colour * 0.4, base_colour[2] * 0.85, t);
    }
    return iris;
}

#endif

// How much brow covers this point: (along 0 inner .. 1 outer, height above the brow curve, mm).
float brow_cover(vec2 d, float grow) {
    float along = d.x;
    if (along < brow_frame.x || along > brow_frame.x + brow_frame.z) return 0.0;   // the hair texture's span
    float inner = clamp((along + 0.05) / 0.09, 0.0, 1.0);   // a rounded inner end
    float outer = clamp((1.07 - along) / 0.3, 0.0, 1.0);    // a tapered outer end
    float half_width = (3.3 - 1.9 * clamp(along, 0.0, 1.0)) * inner * (2.0 - inner) * outer * (2.0 - outer);
    return clamp((half_width + grow - abs(d.y + 0.4)) / 0.9 + 0.5, 0.0, 1.0);
}

// How much of the brow's colour this point takes: its shape, and lit, where the BROWS variant draws (the skin's
// triangles about the brows, render/brows.py), its hairs over a tint of the skin beneath them, a few straying past
// its edge.
float brow_weight(vec2 d, vec4 grad) {
#ifdef BROWS
    if (lighting || albedo) {
        float hairs = textureGrad(brow_texture, (d - brow_frame.xy) / brow_frame.zw, grad.xy / brow_frame.zw,
                                  grad.zw / brow_frame.zw).r;
        float reach = brow_cover(d, BROW_STRAY_MM);
        return max(brow_cover(d, 0.0) * (BROW_TINT + (1.0 - BROW_TINT) * hairs), reach * reach * reach * hairs);
    }
#endif
    return brow_cover(d, 0.0);
}

void main() {
#ifdef BROWS
    vec4 brow_grad = vec4(dFdx(v_detail), dFdy(v_detail));   // (uniform control flow: the brow's lookup is in a branch)
#else
    vec4 brow_grad = vec4(0.0);
#endif
#ifdef LASHES
    float detail_mm = fwidth(v_detail.x);   // mm of detail coordinate per pixel (here: in uniform control flow)
#endif
    vec3 n = normalize(v_normal);
    vec3 to_eye = orthographic ? view_direction : normalize(camera_position - v_position);
    int slot;
    vec3 base;
    float shade = 1.0;
    vec3 wet_normal = n;
    float wetness = 0.0;
    if (v_material == 0) {
        // the capped neck's back side: a silhouette sliver of skin; in texture space a side is the UVs' winding
        if (gl_FrontFacing || v_neck > 0.999 || albedo) {
            if (!gl_FrontFacing) n = -n;
            slot = 0;
            if (use_texture) {
                base = texture(skin_texture, v_uv).rgb;
            } else {
                base = mix(base_colour[0], lip_colour, v_tints.x);
                base = mix(base, brow_colour, 0.9 * brow_weight(v_detail, brow_grad));
            }
            base = mix(base, cavity_colour, v_tints.y);
            shade = 1.0 - 0.85 * v_tints.y;
            float w = nose_wrinkle * v_nose.x;
            if (w > 0.0) {                                // creases across the upper nose: the skin bunches
                float phase = 6.2831853 * v_nose.y / WRINKLE_MM;
                n = normalize(n + 0.4 * w * sin(phase) * vec3(0.0, 1.0, 0.0));
                shade *= 1.0 - 0.22 * w * pow(0.5 + 0.5 * cos(phase), 4.0);
            }
        } else {
            slot = 1;
            base = base_colour[1];
            n = -n;
            shade = 0.55;
        }
#ifdef EYES
    } else if (v_material == 1 || v_material == 2) {
        base = eye_colour(v_material - 1, slot, wet_normal);
        wetness = 1.0;
#endif
#ifdef LASHES
    } else if (v_material == 6) {                       // lashes: strands cut out of the card
        float s = v_detail.x;                             // mm along the margin
        float h = v_detail.y;                             // 0 at the root .. 1 at the tip
        float id = floor(s / lash_strands.x);
        float lean = 0.25 * (hash(id + 3.0) - 0.5) * h;   // strands cross a little toward their tips
        float centre = (id + 0.5 + 0.4 * (hash(id) - 0.5)) * lash_strands.x + lean;
        // seen from afar (strands under a pixel apart) the roots merge into the lash line and the tips,
        // which would alias to loose dots, are left off
        float afar = smoothstep(0.6, 1.5, detail_mm / lash_strands.x);
        float reach = (0.7 + 0.3 * hash(id + 11.0)) * (1.0 - 0.5 * afar);   // uneven lengths
        float half_width = lash_strands.y * (1.0 - 0.85 * h / reach) * sqrt(v_tints.x);  // short ones thin
        half_width = mix(half_width, 0.55 * lash_strands.x, afar * max(1.0 - h / reach, 0.0));
        if (h > reach || abs(s - centre) > half_width) discard;
        slot = 1;
        base = lash_colour;
        if (dot(n, to_eye) < 0.0) n = -n;
#endif
    } else if (v_material == 3) {
        float f = fract(v_detail.x);                      // across one tooth, 0 and 1 at the gaps
        float from_gap = (0.5 - abs(f - 0.5)) * TOOTH_MM;  // mm from the nearest gap
        float h = v_detail.y;                             // mm from the biting edge
        vec2 corner = vec2(TIP_MM) - vec2(from_gap, h);
        bool notch = corner.x > 0.0 && corner.y > 0.0 && length(corner) > TIP_MM;
        if (notch) {                                      // outside a rounded tip: the dark behind
            slot = 1;
            base = cavity_colour;
            shade = 0.15;
        } else if (h > CROWN_MM * (0.8 + 0.8 * f * (1.0 - f))) {
            slot = 5;                                     // gum, scalloped between the teeth
            base = base_colour[5];
        } else {
            slot = 3;
            base = base_colour[3];
            // each tooth bulges: tilt the normal across the tooth; the thin band's normals turn
            // down at the biting edge, so lean them toward the viewer (a tooth's labial face)
            // (front teeth only: seen from the side, the molars' bulges and gaps read as stripes)
            float back = smoothstep(2.0, 4.0, abs(v_detail.x));
            bool lingual = dot(n, to_eye) < 0.0;          // the arch seen from inside: the far side's inner faces
            if (lingual) n = -n;
            n = normalize(n + 0.7 * to_eye + cross(vec3(0.0, 1.0, 0.0), n) * (1.8 * f - 0.9) * (1.0 - back));
            if (lighting || albedo) shade = mix(mix(0.55, 1.0, smoothstep(0.0, 0.35, from_gap)), 0.9, back);  // gaps
            // teeth further back along the arch sit deeper in the mouth, in its shadow
            shade *= mix(1.0, BACK_TEETH_SHADE, smoothstep(2.0, 4.0, abs(v_detail.x)));
            if (lingual && lighting && !albedo) shade *= LINGUAL_SHADE;   // (seen from a viewer: not the bake's)
        }
    } else {
        slot = v_material;   // 4 tongue
        base = base_colour[slot];
        // lit at its tip, in the mouth's shadow further back and toward its edges, which lie under the
        // teeth (evenly lit, it read as a flat slab, cut by the dark back teeth at three-quarter)
        shade = mix(1.0, TONGUE_BACK_SHADE, smoothstep(TONGUE_SHADOW_MM.x, TONGUE_SHADOW_MM.y, v_detail.y))
              * mix(1.0, TONGUE_SIDE_SHADE, smoothstep(0.5, 1.0, abs(v_detail.x)));
    }
    if (albedo) {   // as shown under a unit light: the mouth's shadow in, the light's direction and shine out
        colour = vec4(pow(clamp(base * shade, 0.0, 1.0), vec3(1.0 / 1.15)), 1.0);
        return;
    }
    if (!lighting) {
        colour = vec4(base, 1.0);
        return;
    }
    vec3 light = ambient;
    float spec = 0.0;
    vec3 reflection = vec3(0.0);
    for (int i = 0; i < 2; ++i) {
        float lambert = max(dot(n, light_direction[i]), 0.0);
        light += lambert * light_colour[i];
        vec3 h = normalize(light_direction[i] + to_eye);
        spec += (lambert > 0.0 ? pow(max(dot(n, h), 0.0), shine[slot].y) : 0.0) * shine[slot].x;
#ifdef EYES
        if (wetness > 0.0 && dot(wet_normal, light_direction[i]) > 0.0)   // the tear film mirrors the light
            reflection += pow(max(dot(wet_normal, h), 0.0), wet.y) * wet.x * light_colour[i];
#endif
    }
    vec3 rgb = (base * light + vec3(spec) + reflection) * shade;
    colour = vec4(pow(clamp(rgb, 0.0, 1.0), vec3(1.0 / 1.15)), 1.0);
}
