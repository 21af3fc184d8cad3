// Where rays leave a shaded surface point (SPEC §6), from the triangle the G-buffer names: the
// triangle's vertices come from its mesh's buffers by device address (OBJECT_GEOMETRY_BINDING
// holds, per object, the vertex and index buffers' addresses), so the shading pass needs no
// extra G-buffer target.
//
// The CPU twin is `oracle::shadows::ray_surface`: keep the two alike.

#ifndef RAY_SURFACE_GLSL
#define RAY_SURFACE_GLSL

// The point rays start from and the triangle's unit geometric normal, turned to the side of the
// shading normal. The rest is for visibility.glsl's `trace_mask`: the surface's object (−1:
// none) and the triangle's unit winding normal n = (p1 − p0) × (p2 − p0) / |…|, whose side the
// surface is shaded from tells which of its mesh's sides the rays leave.
struct RaySurface {
    vec3 point;
    vec3 geometric_normal;
    int object;
    vec3 face_normal;
};

// A surface no ray leaves (the shading pass without ray tracing).
RaySurface untraced_surface(vec3 point, vec3 normal) {
    return RaySurface(point, normal, -1, normal);
}

#ifdef RAY_TRACING
// GpuMesh's interleaved vertices (position, normal: six floats) and u32 indices.
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer MeshVertices {
    float values[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer MeshIndices {
    uint values[];
};
layout(set = 0, binding = OBJECT_GEOMETRY_BINDING, std430) readonly buffer ObjectGeometries {
    ObjectGeometry object_geometry[];
};

// Triangle `triangle` of `object`'s mesh: its vertices' positions and (stored) normals.
void fetch_triangle(int object, int triangle, out vec3 p[3], out vec3 normal[3]) {
    uvec4 addresses = object_geometry[object].addresses;
    MeshVertices vertices = MeshVertices(addresses.xy);
    MeshIndices indices = MeshIndices(addresses.zw);
    for (int k = 0; k < 3; ++k) {
        uint first = 6u * indices.values[3 * triangle + k];
        p[k] = vec3(vertices.values[first], vertices.values[first + 1u],
            vertices.values[first + 2u]);
        normal[k] = vec3(vertices.values[first + 3u], vertices.values[first + 4u],
            vertices.values[first + 5u]);
    }
}

// The surface of a triangle with vertices p (normals `normal`, as stored) at the point
// `position` with unit shading normal `n`.
//
// 1. The G-buffer point is interpolated at the pixel centre, which for a multisampled edge pixel
//    may lie outside the triangle, on its plane extended, below a concave neighbour: its
//    barycentrics are clamped into the triangle.
// 2. On a smooth mesh the flat triangle lies inside the smooth surface its normals describe, and
//    rays towards a light low over the surface hit the neighbouring triangles (the "shadow
//    terminator"): the point is lifted onto the smooth surface as in Hanika, "Hacking the Shadow
//    Terminator" (Ray Tracing Gems II, ch. 4): p' = p − Σ b_i·min(0, (p − p_i)·n_i)·n_i.
RaySurface ray_surface_of(vec3 p[3], vec3 normal[3], vec3 position, vec3 n) {
    for (int k = 0; k < 3; ++k) {
        normal[k] = normalize(normal[k]);
    }
    vec3 e1 = p[1] - p[0];
    vec3 e2 = p[2] - p[0];
    vec3 cross_e = cross(e1, e2);
    float area2 = dot(cross_e, cross_e);
    if (!(area2 > 0.0)) {
        // A degenerate triangle (never rasterised with area, but keep the maths finite).
        return untraced_surface(position, n);
    }
    RaySurface surface;
    vec3 ng = cross_e * inversesqrt(area2);
    surface.geometric_normal = dot(ng, n) < 0.0 ? -ng : ng;
    surface.object = -1;
    surface.face_normal = ng;
    // Barycentrics of the point's projection onto the plane, clamped into the triangle.
    vec3 d = position - p[0];
    float b1 = dot(cross(d, e2), cross_e) / area2;
    float b2 = dot(cross(e1, d), cross_e) / area2;
    vec3 b = max(vec3(1.0 - b1 - b2, b1, b2), vec3(0.0));
    b /= b.x + b.y + b.z;
    vec3 inside = b.x * p[0] + b.y * p[1] + b.z * p[2];
    vec3 lifted = inside;
    for (int k = 0; k < 3; ++k) {
        lifted -= b[k] * min(0.0, dot(inside - p[k], normal[k])) * normal[k];
    }
    surface.point = lifted;
    return surface;
}

// The surface of triangle `triangle` of `object` at the G-buffer point `position` with unit
// shading normal `n`.
RaySurface ray_surface(int object, int triangle, vec3 position, vec3 n) {
    vec3 p[3];
    vec3 normal[3];
    fetch_triangle(object, triangle, p, normal);
    RaySurface surface = ray_surface_of(p, normal, position, n);
    surface.object = object;
    return surface;
}

// A ray query's hit: triangle `triangle` of `object` at barycentrics (u, v) of vertices 1 and 2.
// The point and unit shading normal the rasteriser would have interpolated there, and where the
// next rays leave it; the triangle is read once.
RaySurface hit_surface(int object, int triangle, vec2 uv, out vec3 position, out vec3 normal) {
    vec3 p[3];
    vec3 n[3];
    fetch_triangle(object, triangle, p, n);
    float w = 1.0 - uv.x - uv.y;
    position = w * p[0] + uv.x * p[1] + uv.y * p[2];
    normal = normalize(w * n[0] + uv.x * n[1] + uv.y * n[2]);
    RaySurface surface = ray_surface_of(p, n, position, normal);
    surface.object = object;
    return surface;
}
#endif

#endif
