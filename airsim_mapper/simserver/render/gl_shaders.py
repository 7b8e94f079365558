"""GLSL of the OpenGL camera renderer (`gl_renderer.py`): one vertex shader per primitive and one fragment
body shared by the ground, box and sphere programs.

Every fragment takes its pixel's ray (the ray `camera.camera_rays` gives it, to float32 precision) from a
varying the vertex shader set (interpolating it is much cheaper on llvmpipe than computing it from
`gl_FragCoord` and uniforms), hits its primitive analytically along that ray (ground plane, box face
plane, sphere quadratic), and objects write a logarithmic `gl_FragDepth` of the hit distance, so
rasterisation only decides which primitive a pixel sees. `OUTPUTS` is replaced by one
`layout(location = i) out` per requested image kind (see `gl_renderer`).
"""

from __future__ import annotations

HEADER = """#version 410 core
"""

VERTEX_GROUND = """
// drawn last at a constant depth just in front of the far plane: only pixels no object covered run it
uniform vec2 window;  // width, height in pixels
// the world direction of the ray through window point (x, y), not unit length: ray0 + x ray_x + y ray_y
uniform vec3 ray0;
uniform vec3 ray_x;
uniform vec3 ray_y;
noperspective out vec3 v_ray;  // affine in window coordinates, so interpolated exactly (and cheaply)
const vec2 corners[3] = vec2[3](vec2(-1.0, -1.0), vec2(-1.0, 3.0), vec2(3.0, -1.0));
void main() {
    vec2 at = (corners[gl_VertexID] * 0.5 + 0.5) * window;
    v_ray = ray0 + at.x * ray_x + at.y * ray_y;
    gl_Position = vec4(corners[gl_VertexID], 0.999999, 1.0);
}
"""

# boxes: one triangle per vertex triple; every attribute but the position is the face's (flat)
VERTEX_BOX = """
uniform mat4 clip_from_world;
uniform vec3 eye;
in vec3 position;
in vec3 face_normal;
in vec3 face_shade;
in vec3 face_normal_bgr;
in vec3 face_segment_bgr;
flat out vec3 v_point;
flat out vec3 v_normal;
flat out vec3 v_shade;
flat out vec3 v_normal_bgr;
flat out vec3 v_segment_bgr;
out vec3 v_ray;  // towards the surface point: interpolated, it points along the pixel's ray
void main() {
    gl_Position = clip_from_world * vec4(position, 1.0);
    v_ray = position - eye;
    v_point = position;
    v_normal = face_normal;
    v_shade = face_shade;
    v_normal_bgr = face_normal_bgr;
    v_segment_bgr = face_segment_bgr;
}
"""

# spheres: drawn as their bounding cube; the fragment solves the ray-sphere quadratic (an exact impostor)
VERTEX_SPHERE = """
uniform mat4 clip_from_world;
uniform vec3 eye;
in vec3 position;
in vec4 sphere;  // centre xyz, radius
in vec3 base_bgr;
in vec3 face_segment_bgr;
flat out vec4 v_sphere;
flat out vec3 v_base;
flat out vec3 v_segment_bgr;
out vec3 v_ray;
void main() {
    gl_Position = clip_from_world * vec4(position, 1.0);
    v_ray = position - eye;
    v_sphere = sphere;
    v_base = base_bgr;
    v_segment_bgr = face_segment_bgr;
}
"""

# the shared part of every fragment shader: the pixel's ray, and writing one hit (or the sky) to every output
FRAGMENT_COMMON = """
uniform vec3 eye;             // camera position, world NED
uniform vec3 axis;            // the camera's forward axis, world NED
uniform float max_distance;
uniform float max_depth_vis;
uniform vec3 sky_bgr;
uniform vec3 sun;
const float AMBIENT = 0.35;
const float FOG = 1500.0;
OUTPUTS

struct Ray { vec3 dir; float forward; };  // unit world direction, its component along the camera axis

// the ray of this pixel, from the vertex shaders' interpolated direction: the same ray as camera_rays gives
// pixel (u, v) = window point (u + 0.5, v + 0.5), to float32 precision
Ray pixel_ray(vec3 towards) {
    vec3 dir = towards * inversesqrt(dot(towards, towards));
    return Ray(dir, dot(dir, axis));
}

// colours go to 8-bit unsigned integer targets: the conversion truncates, as numpy's astype(uint8) does
uvec4 bgr_of(vec3 value) { return uvec4(uvec3(clamp(value, 0.0, 255.0)), 255u); }
uvec4 gray_of(float value) { return uvec4(uvec3(uint(clamp(value, 0.0, 255.0))), 255u); }

// depths go to float16 targets, whose stores truncate on llvmpipe: round to nearest even first, as numpy's
// astype(float16) does (values from 65520 on become +inf)
float half_rne(float v) {
    uint bits = floatBitsToUint(v);
    return v < 65520.0 ? uintBitsToFloat(bits + 0xFFFu + ((bits >> 13) & 1u)) : uintBitsToFloat(0x7f800000u);
}

// an object's hit at t, unless the ground is as near or nearer along the ray (the ground wins ties)
bool ground_first(Ray ray, float t) { return ray.dir.z > 1e-6 && eye.z < 0.0 && -eye.z / ray.dir.z <= t; }

// objects: the depth that orders them, logarithmic (1e-6 relative at any distance)
void object_depth(float t) { gl_FragDepth = log2(t * 1e4) / log2(2e4 * max_distance); }

// One pixel's outputs, without branches (llvmpipe runs both sides of a branch). t is +inf for the sky,
// which then comes out as the ray caster's sky; shade is the lit base colour (B, G, R 0-255), checker
// says the ground's 2 m checker applies, and the normal and segment colours are black for the sky.
void emit(Ray ray, float t, vec3 shade, bool checker, vec3 normal_bgr, vec3 segment_bgr) {
    float planar = t * ray.forward;
#ifdef WANT_SCENE
    float d = min(t, 1e30);
    float haze = d / (d + FOG);
    float cells = floor(eye.x * 0.5 + ray.dir.x * (d * 0.5)) + floor(eye.y * 0.5 + ray.dir.y * (d * 0.5));
    bool odd = checker && mod(cells, 2.0) != 0.0;
    float keep = (1.0 - haze) * (odd ? 0.85 : 1.0);
    out_scene = bgr_of(shade * keep + sky_bgr * haze);
#endif
#ifdef WANT_PLANAR
    out_planar = half_rne(planar);
#endif
#ifdef WANT_PERSPECTIVE
    out_perspective = half_rne(t);
#endif
#ifdef WANT_SEGMENTATION
    out_segmentation = bgr_of(segment_bgr);
#endif
#ifdef WANT_DEPTH_VIS
    out_depth_vis = gray_of(min(t * (255.0 / max_depth_vis) + 0.5, 255.0));
#endif
#ifdef WANT_DISPARITY
    out_disparity = gray_of(min(255.0 / planar + 0.5, 255.0));
#endif
#ifdef WANT_NORMALS
    out_normals = bgr_of(normal_bgr);
#endif
}

vec3 normal_bgr_of(vec3 n) { return floor((n.zyx + 1.0) * 127.5 + 0.5); }
vec3 lambert(vec3 base, vec3 n) { return base * (AMBIENT + (1.0 - AMBIENT) * clamp(dot(n, sun), 0.0, 1.0)); }
"""

FRAGMENT_GROUND = """
noperspective in vec3 v_ray;
uniform vec3 ground_shade;
uniform vec3 ground_segment_bgr;
uniform vec3 ground_normal_bgr;
void main() {
    Ray ray = pixel_ray(v_ray);
    float ground = -eye.z / ray.dir.z;
    bool hit = ray.dir.z > 1e-6 && eye.z < 0.0 && ground <= max_distance;
    vec3 none = vec3(0.0);
    emit(ray, hit ? ground : uintBitsToFloat(0x7f800000u), ground_shade, hit,
         hit ? ground_normal_bgr : none, hit ? ground_segment_bgr : none);
}
"""

FRAGMENT_BOX = """
in vec3 v_ray;
flat in vec3 v_point;
flat in vec3 v_normal;
flat in vec3 v_shade;
flat in vec3 v_normal_bgr;
flat in vec3 v_segment_bgr;
void main() {
    Ray ray = pixel_ray(v_ray);
    float facing = dot(v_normal, ray.dir);
    if (facing >= 0.0) discard;  // one-sided: a back face (seen from inside the box)
    float t = dot(v_normal, v_point - eye) / facing;
    if (t <= 1e-4 || t > max_distance || ground_first(ray, t)) discard;
    object_depth(t);
    emit(ray, t, v_shade, false, v_normal_bgr, v_segment_bgr);
}
"""

FRAGMENT_SPHERE = """
in vec3 v_ray;
flat in vec4 v_sphere;
flat in vec3 v_base;
flat in vec3 v_segment_bgr;
void main() {
    Ray ray = pixel_ray(v_ray);
    vec3 rel = eye - v_sphere.xyz;
    float b = dot(ray.dir, rel);
    float disc = b * b - (dot(rel, rel) - v_sphere.w * v_sphere.w);
    if (disc < 0.0) discard;
    float t = -b - sqrt(disc);
    // behind the camera, or the camera is inside (one-sided), or hidden by the ground
    if (t <= 1e-4 || t > max_distance || ground_first(ray, t)) discard;
    object_depth(t);
    vec3 n = (eye + ray.dir * t - v_sphere.xyz) / v_sphere.w;
    emit(ray, t, lambert(v_base, n), false, normal_bgr_of(n), v_segment_bgr);
}
"""
