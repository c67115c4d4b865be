/*
 * scene.h - the scene model: plain data holding everything a scene file says,
 * with the manual's defaults filled in, and the builder that creates it.
 *
 * One road for the data: text -> parser -> builder -> struct scene ->
 * (serialize -> wire -> deserialize -> builder) -> acceleration -> tiles.
 * The parser and the scene deserializer both build through the scene_add_*
 * calls below, so a worker rebuilds exactly the model the master parsed, with
 * the same validation.
 *
 * Everything is stored in flat arrays and referenced by uint32 index:
 *   materials[]  every material: named ones and anonymous inline ones
 *   meshes[]     RAW meshes (each loaded once)
 *   objects      every object node: primitives, CSG nodes, instances, by
 *                object index (0 .. n_objects-1); read them through
 *                scene_object() (INSTANCES, below)
 *   defines[]    named object groups (define object NAME ...)
 *   roots[]      top-level objects, in file order
 * An object may only reference objects, defines and materials with a smaller
 * index than its own (or, for roots, any existing one): the graph is acyclic by
 * construction and the builder checks it.
 */
#ifndef PORTRAY_SCENE_H
#define PORTRAY_SCENE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "common/limits.h"
#include "common/vec.h"

#define SCENE_NONE UINT32_MAX /* "no material": inherit from the enclosing object */

/* Where a statement came from, for messages. file is owned by the scene. */
struct src_loc {
	const char *file;
	int line, col;
};

/* ---- errors ---------------------------------------------------------- */

/* Appendix B error levels, used as process exit codes. */
enum {
	ERRLEVEL_OK = 0,
	ERRLEVEL_FATAL = 1, /* level 1: most errors */
	ERRLEVEL_LEVEL2 = 2 /* level 2: samples on shapeless light, heap */
};

/* A formatted error: "file:line:col: error: what (detail) near 'tok'". */
struct scene_error {
	int level;
	char msg[1024];
};

/* Formats into err (printf-style); sets err->level = level. Returns level. */
int scene_errorf(struct scene_error *err, int level, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));

/* ---- camera and image ------------------------------------------------ */

enum filter_kind {
	FILTER_STANDARD,
	FILTER_ADAPTIVE,
	FILTER_SUPERSAMPLE,
	FILTER_DISK,
	FILTER_LENS
};

struct scene_filter {
	enum filter_kind kind;
	/* adaptive */
	double threshold;   /* default 0.2 */
	int max_depth;      /* default 3 */
	int cache_size;     /* default 1000 (or the image intersect-buffer) */
	double relax;       /* default 1.2 */
	/* super-sample */
	int x_samples;      /* default 2 */
	int y_samples;      /* default 2 */
	/* disk and lens */
	double radius;      /* disk default 0.707 (pixels), lens default 0.1 */
	int samples;        /* disk default 4, lens default 4 */
	double focal_length; /* lens default 1000.0 */
	struct src_loc loc;
};

struct scene_camera {
	vec3 look_at;   /* default (0 0 0) */
	vec3 drop_line; /* default (0 -1 0): the image's downward direction */
	vec3 look_from; /* default (0 0 10): on +z, looking at the origin */
	double depth;   /* default 0.028 */
	double x_size;  /* default 0.032: film width  -> image width */
	double y_size;  /* default 0.024: film height -> image height */
	struct scene_filter filters[LIM_FILTERS]; /* in the order written */
	int n_filters;
	bool set;       /* a camera statement was seen */
	struct src_loc loc;
};

struct scene_image {
	int xsize, ysize;       /* default 320 x 240 */
	bool no_shadows;
	bool no_reflections;
	bool nonstop;
	int intersect_buffer;   /* default 1000: adaptive corner cache entries */
	bool set;
	struct src_loc loc;
};

/* ---- primitives ------------------------------------------------------ */

enum prim_kind {
	PRIM_SPHERE,
	PRIM_PLANE,
	PRIM_CYLINDER,
	PRIM_BOX,
	PRIM_TRIANGLE,
	PRIM_RAW,
	PRIM_CSG,
	PRIM_DISK,
	PRIM_POLYGON,
	PRIM_INSTANCE, /* use of a defined object */
	PRIM_KIND_COUNT
};

enum csg_op { CSG_UNION, CSG_INTERSECT, CSG_SUBTRACT };

struct prim_sphere {
	vec3 centre;   /* default (0 0 0) */
	double radius; /* default 1 */
	vec3 pole;     /* default (0 1 0): direction of the north pole */
	vec3 equator;  /* default (1 0 0): where longitude 0 starts */
};

/* plane and disk share one shape; radius is used by the disk only */
struct prim_plane {
	vec3 position; /* default (0 0 0) */
	vec3 normal;   /* default (0 1 0) */
	vec3 x_axis;   /* default: derived perpendicular to normal */
	vec3 y_axis;   /* default: normal x x_axis */
	bool has_axes; /* x_axis/y_axis were written (else derived) */
	double radius; /* disk only, default 1 */
};

struct prim_cylinder {
	vec3 from, to; /* default (0 0 0) -> (0 1 0) */
	double radius; /* default 1 */
	bool capped;
};

struct prim_box {
	vec3 a, b; /* default (0 0 0), (1 1 1); any two opposite corners */
};

struct prim_triangle {
	vec3 a, b, c;
	vec3 na, nb, nc;  /* valid when has_normals */
	bool has_normals; /* all three normal-a/b/c given */
};

struct prim_raw {
	uint32_t mesh;    /* index into scene.meshes */
};

struct prim_csg {
	enum csg_op op;
	uint32_t operand1, operand2; /* object indices, both < this object's */
};

/* Polygon: one or more coplanar contours, filled by the even-odd rule. */
struct prim_polygon {
	uint32_t n_contours;
	uint32_t *contour_start; /* n_contours+1 offsets into points (owned) */
	vec3 *points;            /* all contours' vertices (owned) */
	uint32_t n_points;
};

struct prim_instance {
	uint32_t define; /* index into scene.defines */
};

/* ---- objects ---------------------------------------------------------- */

struct scene_object {
	enum prim_kind kind;
	union {
		struct prim_sphere sphere;
		struct prim_plane plane; /* PRIM_PLANE and PRIM_DISK */
		struct prim_cylinder cylinder;
		struct prim_box box;
		struct prim_triangle triangle;
		struct prim_raw raw;
		struct prim_csg csg;
		struct prim_polygon polygon;
		struct prim_instance instance;
	} u;
	mat34 xform;      /* object -> parent space, transforms in written order */
	bool has_xform;   /* false: xform is the identity */
	uint32_t material; /* SCENE_NONE: inherit from enclosing object/instance */
	struct src_loc loc;
};

/*
 * INSTANCES. A scene may hold millions of instances (issue 13: a million of
 * them in at most 100 bytes each, the whole process), so an instance is not
 * a 280-byte struct scene_object but a 48-byte struct scene_inst: its
 * translation, its define and material, its source location, and the index
 * of its transform's 3x3 part in a table of such parts (where neighbours
 * written with the same rotation share one entry). Bit i of inst_bits says
 * whether object i is an instance; its rank among the instances (the
 * count in inst_rank[i / 64] of those below object 64 (i / 64), plus the
 * bits below i in its word) indexes insts[], and i minus that rank indexes
 * objs[] (every other kind, as written): 1.5 bits per object, no table of
 * indices. scene_object() gives any object as a
 * struct scene_object (an instance expanded into the caller's buffer); the
 * expansion gives back the very bits that were added (the 3x3 part is
 * compared bit for bit, -0 included), so nothing reading a scene can tell.
 * An instance added without has_xform reads back with the identity.
 */
#define SCENE_LIN_NONE UINT32_MAX     /* scene_inst.lin: no transform (has_xform false) */
#define SCENE_LIN_IDENTITY (UINT32_MAX - 1) /* a translation only: the 3x3 part is the identity */

struct scene_inst {
	vec3 t;            /* the transform's translation column (0 without one) */
	uint32_t lin;      /* SCENE_LIN_NONE, SCENE_LIN_IDENTITY or an index into lins */
	uint32_t define;   /* index into scene.defines */
	uint32_t material; /* SCENE_NONE: inherit */
	uint32_t file;     /* index into scene.files; SCENE_NONE: no file */
	int32_t line, col;
};

/* A RAW mesh after welding/rotation; shared by every object that uses it. */
struct scene_mesh {
	char *file;            /* path as written in the scene (owned) */
	uint32_t n_vertices;
	uint32_t n_triangles;
	vec3 *vertices;        /* n_vertices (owned) */
	vec3 *normals;         /* n_vertices when smoothed, else NULL (owned) */
	uint32_t *tris;        /* 3 * n_triangles vertex indices (owned) */
	/* options as written (kept for --check and for the serializer) */
	double weld;           /* default 0.00001 */
	bool smooth;
	vec3 rotation;         /* degrees about x, y, z, applied in that order */
	vec3 at;               /* default (0 0 0) */
};

/* define object NAME <objects> ; */
struct scene_define {
	char *name;            /* owned; names compare case-insensitively */
	uint32_t *objects;     /* member object indices (owned) */
	uint32_t n_objects;
	struct src_loc loc;
};

/* ---- lights ----------------------------------------------------------- */

enum light_shape { LIGHT_POINT, LIGHT_SPHERE, LIGHT_CYLINDER, LIGHT_BOX };

struct scene_light {
	vec3 colour;        /* default (1 1 1) */
	vec3 position;      /* default (0 0 0) */
	enum light_shape shape;
	struct prim_sphere sphere;     /* LIGHT_SPHERE */
	struct prim_cylinder cylinder; /* LIGHT_CYLINDER */
	struct prim_box box;           /* LIGHT_BOX */
	int samples;        /* default 1; only with a shape */
	double fall_off;    /* default 0: none; 1 linear; 2 squared; any >= 0 */
	bool no_shadows;
	struct src_loc loc;
};

/* ---- materials and shaders --------------------------------------------- */

enum shader_kind {
	SHADER_NONE,
	SHADER_BRICKS,
	SHADER_TILES,
	SHADER_CHEQUERS,
	SHADER_BUMPY,
	SHADER_NOISE,
	SHADER_FADES,
	SHADER_TURB3D
};

struct fades_entry {
	double dist;        /* distance over which to fade into this entry */
	vec3 colour;        /* colours list */
	uint32_t material;  /* materials list (SCENE_NONE in a colours list) */
};

/*
 * Shader parameters. Material arguments are material indices (smaller than
 * the owning material's index). Defaults: docs/language.md.
 */
struct scene_shader {
	enum shader_kind kind;
	double size;              /* all: feature size */
	uint32_t mat_a, mat_b;    /* bricks: mortar, brick; tiles: face, grout;
				     chequers: material-a, material-b;
				     bumpy/noise/turb3d: material (mat_a) */
	double tile_width, grout_width; /* tiles */
	int terms;                /* bumpy, turb3d */
	vec3 axis_size;           /* bumpy xsize ysize zsize */
	double saturation, depth; /* bumpy; turb3d depth */
	double variance;          /* noise */
	vec3 colour;              /* noise base colour */
	vec3 axis;                /* fades */
	bool fades_materials;     /* fades: materials list (else colours) */
	struct fades_entry *fades; /* owned */
	uint32_t n_fades;
};

struct scene_material {
	char *name;           /* owned; NULL for anonymous inline materials */
	vec3 diff_colour;     /* default (1 1 1) */
	vec3 spec_colour;     /* default (1 1 1) */
	vec3 tran_colour;     /* default (1 1 1) */
	double diffuse;       /* diffuse-reflection, default 1.0 */
	double specular;      /* specular-reflection, default 0.0 */
	double spec_power;    /* specular-power, default 20 */
	double reflection;    /* default 0 */
	double transparency;  /* default 0 */
	double ior;           /* refractive-index, default 1.0 */
	struct scene_shader shader; /* kind SHADER_NONE when none */
	struct src_loc loc;
};

/* ---- the scene --------------------------------------------------------- */

struct scene {
	struct scene_camera camera;
	struct scene_image image;

	struct scene_light *lights;
	uint32_t n_lights, cap_lights;
	struct scene_material *materials;
	uint32_t n_materials, cap_materials;
	struct scene_mesh *meshes;
	uint32_t n_meshes, cap_meshes;
	/* objects: n_objects indices, instances told apart by inst_bits (INSTANCES) */
	uint64_t *inst_bits;         /* bit i: object i is an instance */
	uint32_t *inst_rank;         /* per word: the instances below it */
	uint32_t n_objects, cap_words;
	struct scene_object *objs;   /* every object but instances */
	uint32_t n_objs, cap_objs;
	struct scene_inst *insts;    /* instances */
	uint32_t n_insts, cap_insts;
	mat34 *lins;                 /* instances' 3x3 parts (translation column 0) */
	uint32_t n_lins, cap_lins;
	uint32_t last_file;          /* files[] index of the last instance's file (a cache) */
	struct scene_define *defines;
	uint32_t n_defines, cap_defines;
	uint32_t *roots;
	uint32_t n_roots, cap_roots;

	/* interned file names referenced by src_loc.file (owned) */
	char **files;
	uint32_t n_files, cap_files;
};

/* Whether object i is an instance (stored as a struct scene_inst). */
static inline bool scene_is_inst(const struct scene *s, uint32_t i) { return s->inst_bits[i >> 6] >> (i & 63) & 1; }
/* The instances among objects 0 .. i-1: the word's rank plus the bits
 * below i, counted inline (no popcount instruction is assumed: generic
 * x86-64 builds call a library function for __builtin_popcountll). */
static inline uint32_t scene_inst_rank(const struct scene *s, uint32_t i)
{
	uint64_t x = s->inst_bits[i >> 6] & ((UINT64_C(1) << (i & 63)) - 1);
	uint32_t r = s->inst_rank[i >> 6];
	if (!x)
		return r;
	x = x - ((x >> 1) & UINT64_C(0x5555555555555555));
	x = (x & UINT64_C(0x3333333333333333)) + ((x >> 2) & UINT64_C(0x3333333333333333));
	x = (x + (x >> 4)) & UINT64_C(0x0f0f0f0f0f0f0f0f);
	return r + (uint32_t)((x * UINT64_C(0x0101010101010101)) >> 56);
}
/* The compact record of instance object i (scene_is_inst(s, i)). */
static inline const struct scene_inst *scene_inst_at(const struct scene *s, uint32_t i)
{
	return &s->insts[scene_inst_rank(s, i)];
}
/* Object i that is not an instance (!scene_is_inst(s, i)). */
static inline const struct scene_object *scene_full_at(const struct scene *s, uint32_t i)
{
	return &s->objs[i - scene_inst_rank(s, i)];
}
/* The kind of object i. */
static inline enum prim_kind scene_kind(const struct scene *s, uint32_t i)
{
	return scene_is_inst(s, i) ? PRIM_INSTANCE : scene_full_at(s, i)->kind;
}
/* Expands instance record in into *o (a struct scene_object of kind
 * PRIM_INSTANCE, exactly as it was added). */
void scene_inst_expand(const struct scene *s, const struct scene_inst *in, struct scene_object *o);
/* The transform of instance record in (the identity without one). */
void scene_inst_xform(const struct scene *s, const struct scene_inst *in, mat34 *m);
/*
 * Object i (< n_objects): a pointer into the scene for every kind but
 * instances, which are expanded into *tmp (then the pointer is tmp). Valid
 * until the scene changes (and while *tmp lives).
 */
static inline const struct scene_object *scene_object(const struct scene *s, uint32_t i, struct scene_object *tmp)
{
	if (!scene_is_inst(s, i))
		return scene_full_at(s, i);
	scene_inst_expand(s, scene_inst_at(s, i), tmp);
	return tmp;
}
/* Object i by value (tests and tools; polygon arrays stay the scene's). */
struct scene_object scene_object_at(const struct scene *s, uint32_t i);

/* Defaults, exactly as docs/language.md states them. */
void scene_camera_defaults(struct scene_camera *c);
void scene_image_defaults(struct scene_image *im);
void scene_filter_defaults(struct scene_filter *f, enum filter_kind kind);
void scene_light_defaults(struct scene_light *l);
void scene_material_defaults(struct scene_material *m);
void scene_shader_defaults(struct scene_shader *s, enum shader_kind kind);
void scene_object_defaults(struct scene_object *o, enum prim_kind kind);

/* New empty scene with camera and image defaults; NULL when out of memory. */
struct scene *scene_new(void);
/* Frees the scene and everything it owns; accepts NULL. */
void scene_free(struct scene *s);

/* Returns a scene-owned copy of a file name for src_loc.file (NULL on OOM). */
const char *scene_intern_file(struct scene *s, const char *name);

/*
 * Builder. Each call validates its argument (finite numbers, indices in
 * range and smaller than the new item's, positive sizes where required) and
 * on success appends a deep copy... except where "takes ownership" is said:
 * then the owned pointers inside the argument move into the scene on success
 * AND on failure (the scene frees them), so callers never double-free.
 * Each returns 0 on success or an error level with err filled in.
 */
int scene_set_camera(struct scene *s, const struct scene_camera *c, struct scene_error *err);
int scene_set_image(struct scene *s, const struct scene_image *im, struct scene_error *err);
int scene_add_light(struct scene *s, const struct scene_light *l, struct scene_error *err);
/* takes ownership of m->name and m->shader.fades */
int scene_add_material(struct scene *s, struct scene_material *m, uint32_t *id, struct scene_error *err);
/* takes ownership of the mesh's arrays and file */
int scene_add_mesh(struct scene *s, struct scene_mesh *mesh, uint32_t *id, struct scene_error *err);
/* takes ownership of polygon arrays */
int scene_add_object(struct scene *s, struct scene_object *o, uint32_t *id, struct scene_error *err);
/* takes ownership of d->name and d->objects */
int scene_add_define(struct scene *s, struct scene_define *d, uint32_t *id, struct scene_error *err);
int scene_add_root(struct scene *s, uint32_t object, struct scene_error *err);

/* Lookup by name, case-insensitive; SCENE_NONE when absent. Latest wins. */
uint32_t scene_find_material(const struct scene *s, const char *name);
uint32_t scene_find_define(const struct scene *s, const char *name);

/* The material used where none is given: white and matt (docs/language.md). */
const struct scene_material *scene_default_material(void);

/* Counts for --check and benchmarks. The "as drawn" counts saturate at
 * UINT64_MAX, which therefore means "UINT64_MAX or more". */
struct scene_stats {
	uint32_t by_kind[PRIM_KIND_COUNT]; /* objects by kind, as stored */
	uint64_t triangles;     /* mesh triangles counted once per mesh */
	uint64_t triangles_instanced; /* as drawn: through every instance */
	uint64_t prims_instanced; /* primitives as drawn, through every instance
				     and CSG operand: spheres, planes, cylinders,
				     boxes, triangles, disks, polygons, and raw
				     meshes counting one each (CSG nodes and
				     instances themselves count none) */
	uint32_t materials_named, materials_anon;
};
void scene_stats(const struct scene *s, struct scene_stats *st);

const char *scene_prim_name(enum prim_kind k);
const char *scene_filter_name(enum filter_kind k);
const char *scene_shader_name(enum shader_kind k);

/* Builds the transform for one written transform keyword; angles in degrees. */
enum xform_op { XF_SHRINK, XF_STRETCH, XF_TRANSLATE, XF_ROTATE };
/* axis: 0=x 1=y 2=z (ignored for translate). Returns 0 if the op is degenerate
 * (shrink/stretch by 0 or a non-finite number). */
int scene_xform_op(mat34 *m, enum xform_op op, int axis, double amount, vec3 v);

#endif
