/*
 * limits.h - every limit portray enforces, in one place, each with its reason.
 *
 * Untrusted input (scene files, RAW files, bytes off a socket) is checked
 * against these before anything is allocated. A test build may shrink them
 * (-DPORTRAY_SMALL_LIMITS) to give bugs a chance, as Lua's ltests.h does.
 */
#ifndef PORTRAY_LIMITS_H
#define PORTRAY_LIMITS_H

/* include nesting; the issue asks for 32, deeper is a cycle in practice */
#define LIM_INCLUDE_DEPTH 32
/* one token (names, file names, numbers): longer is not a real scene */
#define LIM_TOKEN_LEN 1024
/* scene/camera/include file size: 1 GiB keeps size_t arithmetic trivially safe */
#define LIM_FILE_BYTES (1024ull * 1024 * 1024)
/* RAW mesh file size: 2 GiB is ~30M triangles of text */
#define LIM_RAW_BYTES (2048ull * 1024 * 1024)
/* triangles in one RAW mesh: indices are uint32 */
#define LIM_MESH_TRIANGLES (64u * 1024 * 1024)
/* largest RAW coordinate magnitude: keeps edge cross products and squared
 * distances finite (no real model comes near it) */
#define LIM_RAW_COORD 1e100
/* objects (every primitive, CSG node and instance) in one scene */
#define LIM_OBJECTS (64u * 1024 * 1024)
/* named materials, definitions, lights, meshes */
#define LIM_MATERIALS (1u << 20)
#define LIM_DEFINES (1u << 20)
#define LIM_LIGHTS 65536u
#define LIM_MESHES 65536u
/* CSG nesting and define nesting: recursion in the tracer is bounded by these */
#define LIM_CSG_DEPTH 64
#define LIM_DEFINE_DEPTH 64
/* shader materials nest (a bumpy over a noise over a fades ...) */
#define LIM_SHADER_DEPTH 16
/* entries in a fades list */
#define LIM_FADES_ENTRIES 256
/* polygon: contours and vertices */
#define LIM_POLY_CONTOURS 4096u
#define LIM_POLY_VERTICES (1u << 20)
/* filters in a camera: 8 layered filters is already absurd (the manual's 900 rays) */
#define LIM_FILTERS 16
/* samples of any one filter or light; keeps rays per pixel bounded */
#define LIM_SAMPLES 4096
/* eye rays the layered filters (super-sample, disk, lens) multiply each
 * base sample into: the manual's 900 is "obviously too many"; past 2^20 a
 * layered camera (4096^16 otherwise) would never finish a pixel */
#define LIM_RAYS_PER_SAMPLE (1u << 20)
/* adaptive filter max-depth: 2^depth sub-pixels per side */
#define LIM_ADAPTIVE_DEPTH 8
/* image size in pixels, per side and in total (RGB8 buffer fits easily) */
#define LIM_IMAGE_SIDE 65536
#define LIM_IMAGE_PIXELS (256ull * 1024 * 1024)
/* shader terms (bumpy, turb3d octaves) */
#define LIM_TERMS 32
/* reflection/refraction recursion: past 10 bounces a ray's weight is below
 * what an 8-bit pixel shows in any sane scene (the weight cut-off stops most
 * paths much earlier) */
#define LIM_TRACE_DEPTH 10
/* surfaces a shadow ray walks through (transparent objects) before the
 * light counts as blocked: bounds the work per shadow ray */
#define LIM_SHADOW_HITS 64

#endif
