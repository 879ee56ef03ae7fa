/* messages.h — every message body of the deformd wire protocol: types, limits, wire error codes,
 * one C struct per body and its pure encode/decode functions (no I/O). Spec: proto/PROTOCOL.md.
 *
 * Conventions shared by every function below:
 *  - Encoders `df_msg_X_encode(const df_msg_X *m, df_buf *out, df_error *err)` validate `m`
 *    exactly like the decoder would, then APPEND the payload (no frame header) to `out`.
 *    Return DF_OK, DF_EINVAL (bad field, message names it), DF_ELIMIT (count over a limit) or
 *    DF_ENOMEM; `out` is unchanged on error. Wrap the payload in a frame with df_frame_begin /
 *    df_frame_end (proto/frame_codec.h).
 *  - Decoders `df_msg_X_decode(const uint8_t *p, size_t n, df_msg_X *m, df_error *err)` parse a
 *    whole payload of `n` bytes. They check every length, count against the bytes present, enum
 *    range, index range, NaN/Inf, and reject trailing bytes. Return DF_OK or
 *    DF_EPROTO_TRUNCATED / DF_EPROTO_TRAILING / DF_EINVAL / DF_ELIMIT / DF_ENOMEM, with `*m`
 *    untouched on error (nothing to free).
 *  - Decoded arrays and strings: strings up to DF_MAX_NAME_LEN are copied into fixed char arrays
 *    (NUL-terminated). Everything else declared as a non-const pointer (`float *xyz`, `char
 *    *path`, ...) is malloc'd by the decoder and released by that message's df_msg_X_free (which
 *    also accepts a zeroed struct). Fields declared `const uint8_t *` (raw byte blobs: mesh file
 *    bytes, auth token, ping data) POINT INTO THE PAYLOAD `p` and are valid only while it is.
 *  - On the encode side every pointer field is only read; NULL is fine when its count is 0.
 *  - Vertex indices are int32_t in memory (as in core/mesh/mesh.h) and u32 on the wire, always
 *    < DF_MAX_MESH_VERTICES (so < 2^31). Wire floats: IEEE-754 little-endian; positions and
 *    displacements float32, parameters float64.
 */
#ifndef DF_PROTO_MESSAGES_H
#define DF_PROTO_MESSAGES_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh_io.h"
#include "proto/buf.h"
#include "proto/frame.h"
#include "proto/frame_codec.h"
#include "proto/wire_error.h"

/* Limits (reported in hello), message types, feature bits, enums and brush defaults: every
 * number of the wire comes from proto/wire_schema.h (the one source of truth, checked against
 * the Python client and PROTOCOL.md by tests/integration/test_schema.py). */
#include "proto/wire_schema.h"

_Static_assert(DF_MAX_ERROR_MSG_LEN == DF_ERROR_MSG_MAX - 1, "error message limit vs df_error");

/* -------------------------------------------------------------------------- message types
 * Request body -> reply body (or event body) per type: see DF_WIRE_MSG_TYPES. */
#define DF_X_TYPE(n, v, name, req, rep, ev) DF_MSG_##n = (v),
typedef enum df_msg_type { DF_WIRE_MSG_TYPES(DF_X_TYPE) } df_msg_type;
#undef DF_X_TYPE

/* 1 if `type` is one of the values above, else 0. */
int df_msg_type_valid(uint16_t type);

/* Stable lower-case name ("brush_begin"), "unknown" for anything else. */
const char *df_msg_type_name(uint16_t type);

/* ------------------------------------------------------------------------------ enums
 * One C enum per wire enum of proto/wire_schema.h (meanings there), and the largest value of
 * each contiguous 1..MAX enum. Mappings to core's enums: proto/wire_core_map.h. */
#define DF_X_ENUM(prefix, n, v) prefix##n = (v),
#define DF_X_FEAT(n, v) DF_X_ENUM(DF_FEAT_, n, v)
typedef enum df_feature { DF_WIRE_FEATURES(DF_X_FEAT) } df_feature;
#define DF_X_LSRC(n, v) DF_X_ENUM(DF_LOAD_, n, v)
typedef enum df_load_source { DF_WIRE_LOAD_SOURCES(DF_X_LSRC) } df_load_source;
#define DF_X_LOPT(n, v) DF_X_ENUM(DF_LOAD_OPT_, n, v)
enum { DF_WIRE_LOAD_OPTS(DF_X_LOPT) };
#define DF_X_WFMT(n, v) DF_X_ENUM(DF_WFMT_, n, v)
typedef enum df_wire_format { DF_WIRE_FORMATS(DF_X_WFMT) } df_wire_format;
#define DF_X_WKIND(n, v) DF_X_ENUM(DF_WKIND_, n, v)
typedef enum df_wire_mesh_kind { DF_WIRE_MESH_KINDS(DF_X_WKIND) } df_wire_mesh_kind;
#define DF_X_BRUSH(n, v) DF_X_ENUM(DF_BRUSH_, n, v)
typedef enum df_brush_type { DF_WIRE_BRUSH_TYPES(DF_X_BRUSH) } df_brush_type;
#define DF_X_INTEG(n, v) DF_X_ENUM(DF_INTEG_, n, v)
typedef enum df_integrator { DF_WIRE_INTEGRATORS(DF_X_INTEG) } df_integrator;
#define DF_X_BP(n, v) DF_X_ENUM(DF_BP_, n, v)
typedef enum df_brush_param_id { DF_WIRE_BRUSH_PARAMS(DF_X_BP) } df_brush_param_id;
#define DF_X_ENERGY(n, v) DF_X_ENUM(DF_ENERGY_, n, v)
typedef enum df_energy { DF_WIRE_ENERGIES(DF_X_ENERGY) } df_energy;
#define DF_X_CHANGE(n, v) DF_X_ENUM(DF_CHANGE_, n, v)
typedef enum df_change_kind { DF_WIRE_CHANGE_KINDS(DF_X_CHANGE) } df_change_kind;
#define DF_X_DISP(n, v) DF_X_ENUM(DF_DISP_, n, v)
typedef enum df_disp_encoding { DF_WIRE_DISP_ENCODINGS(DF_X_DISP) } df_disp_encoding;
#define DF_X_MOVE(n, v) DF_X_ENUM(DF_MOVE_, n, v)
typedef enum df_move_status { DF_WIRE_MOVE_STATUSES(DF_X_MOVE) } df_move_status;
#define DF_X_SECTION(n, v) DF_X_ENUM(DF_SECTION_, n, v)
typedef enum df_mesh_section { DF_WIRE_MESH_SECTIONS(DF_X_SECTION) } df_mesh_section;
#define DF_X_PIN(n, v) DF_X_ENUM(DF_PIN_, n, v)
enum { DF_WIRE_PIN_FLAGS(DF_X_PIN) };
#define DF_X_GM(n, v) DF_X_ENUM(DF_GET_MESH_, n, v)
enum { DF_WIRE_GET_MESH_FLAGS(DF_X_GM) };
#define DF_X_SUB(n, v) DF_X_ENUM(DF_SUBSCRIBE_, n, v)
enum { DF_WIRE_SUBSCRIBE_FLAGS(DF_X_SUB) };
#define DF_X_BS(n, v) DF_X_ENUM(DF_BS_, n, v)
enum { DF_WIRE_BRUSH_STATE_FIELDS(DF_X_BS) };
#define DF_X_ORIGIN(n, v) DF_X_ENUM(DF_ORIGIN_, n, v)
typedef enum df_origin_kind { DF_WIRE_ORIGINS(DF_X_ORIGIN) } df_origin_kind;
#define DF_X_CURSOR(n, v) DF_X_ENUM(DF_CURSOR_, n, v)
enum { DF_WIRE_CURSOR_FLAGS(DF_X_CURSOR) };
#define DF_X_DEVCLASS(n, v) DF_X_ENUM(DF_DEVCLASS_, n, v)
enum { DF_WIRE_DEV_CLASSES(DF_X_DEVCLASS) };
#define DF_X_DEVBACKEND(n, v) DF_X_ENUM(DF_DEVBACKEND_, n, v)
enum { DF_WIRE_DEV_BACKENDS(DF_X_DEVBACKEND) };
#define DF_X_DEVSTATE(n, v) DF_X_ENUM(DF_DEVSTATE_, n, v)
enum { DF_WIRE_DEV_STATES(DF_X_DEVSTATE) };
#define DF_X_AUTHM(n, v) DF_X_ENUM(DF_AUTH_, n, v)
enum { DF_WIRE_AUTH_METHODS(DF_X_AUTHM) }; /* DF_AUTH_HMAC_CHALLENGE, DF_AUTH_HMAC_PROOF */
#define DF_X_AMODE(n, v) DF_X_ENUM(DF_ACCESS_MODE_, n, v)
enum { DF_WIRE_ACCESS_MODES(DF_X_AMODE) }; /* DF_ACCESS_MODE_OPEN .. OWNER */
#define DF_X_AFLAG(n, v) DF_X_ENUM(DF_ACCESS_, n, v)
enum { DF_WIRE_ACCESS_FLAGS(DF_X_AFLAG) }; /* DF_ACCESS_NEW_KEY */
#define DF_X_STAGE(n, v) DF_X_ENUM(DF_STAGE_, n, v)
typedef enum df_work_stage { DF_WIRE_WORK_STAGES(DF_X_STAGE) } df_work_stage;
#define DF_X_WOPT(n, v) DF_X_ENUM(DF_WORK_OPT_, n, v)
enum { DF_WIRE_WORK_OPTS(DF_X_WOPT) };
#define DF_X_PEERF(n, v) DF_X_ENUM(DF_PEER_, n, v)
enum { DF_WIRE_PEER_FLAGS(DF_X_PEERF) }; /* DF_PEER_SELF, _EDIT, _SHM */
#define DF_X_TRANSPORT(n, v) DF_X_ENUM(DF_TRANSPORT_, n, v)
enum { DF_WIRE_TRANSPORTS(DF_X_TRANSPORT) }; /* DF_TRANSPORT_UNIX, _TCP */
#define DF_X_SENC(n, v) DF_X_ENUM(DF_STREAM_ENC_, n, v)
enum { DF_WIRE_STREAM_ENCS(DF_X_SENC) }; /* DF_STREAM_ENC_QUANTIZED, DF_STREAM_ENC_ZSTD */

/* The wire owns these numbers; where core/mesh has the same enum (load format, mesh kind) the
 * daemon and the client pass values through, so each value is checked equal here. */
#define DF_X_FMT_EQ(n, v) _Static_assert(DF_WFMT_##n == (int)DF_FMT_##n, "wire format " #n);
DF_WIRE_FORMATS(DF_X_FMT_EQ)
_Static_assert(DF_WKIND_POLYLINE == (int)DF_MESH_POLYLINE && DF_WKIND_TRIANGLE ==
               (int)DF_MESH_TRIANGLE && DF_WKIND_TET == (int)DF_MESH_TET, "wire mesh kinds");

/* OR of every bit of a flags list / count of an enum list. */
#define DF_X_OR(n, v) | (v)
#define DF_X_COUNT(n, v) +1
#define DF_FEAT_ALL (0u DF_WIRE_FEATURES(DF_X_OR)) /* what this build implements */
#define DF_FEAT_DECODE_MASK DF_FEAT_ALL /* accepted in hello / hello_reply */
#define DF_LOAD_OPTS_ALL (0u DF_WIRE_LOAD_OPTS(DF_X_OR))
#define DF_BS_ALL (0u DF_WIRE_BRUSH_STATE_FIELDS(DF_X_OR))  /* every brush state field */
#define DF_CURSOR_FLAGS_ALL (0u DF_WIRE_CURSOR_FLAGS(DF_X_OR))
#define DF_WORK_OPTS_ALL (0u DF_WIRE_WORK_OPTS(DF_X_OR))
#define DF_STREAM_ENC_ALL (0u DF_WIRE_STREAM_ENCS(DF_X_OR))
/* the options bits valid in handles and brush_begin (KELVINLET_GUESS, POLISH: handle_move only) */
#define DF_WORK_OPTS_NOT_MOVE ((uint32_t)DF_WORK_OPT_PROGRESS)
#define DF_STAGE_MAX (0 DF_WIRE_WORK_STAGES(DF_X_COUNT)) /* stages this build sends: 1..MAX */
#define DF_ORIGIN_MAX (0 DF_WIRE_ORIGINS(DF_X_COUNT) - 1)    /* origins are 0..DF_ORIGIN_MAX */
#define DF_FMT_MAX (0 DF_WIRE_FORMATS(DF_X_COUNT) - 1)        /* formats are 0..DF_FMT_MAX */
#define DF_BRUSH_TYPE_MAX (0 DF_WIRE_BRUSH_TYPES(DF_X_COUNT)) /* the 1..MAX enums: */
#define DF_BP_MAX (0 DF_WIRE_BRUSH_PARAMS(DF_X_COUNT))
#define DF_ENERGY_MAX (0 DF_WIRE_ENERGIES(DF_X_COUNT))
#define DF_CHANGE_MAX (0 DF_WIRE_CHANGE_KINDS(DF_X_COUNT))
#define DF_MOVE_STATUS_MAX (0 DF_WIRE_MOVE_STATUSES(DF_X_COUNT) - 1) /* 0..MAX */
#define DF_SECTION_MAX (0 DF_WIRE_MESH_SECTIONS(DF_X_COUNT))
#define DF_DEVCLASS_MAX (0 DF_WIRE_DEV_CLASSES(DF_X_COUNT) - 1)   /* 0..MAX */
#define DF_DEVBACKEND_MAX (0 DF_WIRE_DEV_BACKENDS(DF_X_COUNT))    /* 1..MAX */
#define DF_DEVSTATE_MAX (0 DF_WIRE_DEV_STATES(DF_X_COUNT))        /* 1..MAX */
#define DF_ACCESS_MODE_MAX (0 DF_WIRE_ACCESS_MODES(DF_X_COUNT))   /* 1..MAX */
#define DF_ACCESS_FLAGS_ALL (0u DF_WIRE_ACCESS_FLAGS(DF_X_OR))
#define DF_PEER_FLAGS_ALL (0u DF_WIRE_PEER_FLAGS(DF_X_OR))
#define DF_TRANSPORT_MAX (0 DF_WIRE_TRANSPORTS(DF_X_COUNT))      /* 1..MAX */
_Static_assert(DF_TRANSPORT_TCP == DF_TRANSPORT_MAX, "the transports stay contiguous");
_Static_assert(DF_ACCESS_MODE_OWNER == DF_ACCESS_MODE_MAX, "the access modes stay contiguous");
_Static_assert(DF_DEVCLASS_PEN == DF_DEVCLASS_MAX && DF_DEVBACKEND_REPLAY == DF_DEVBACKEND_MAX &&
               DF_DEVSTATE_UNPLUGGED == DF_DEVSTATE_MAX, "the device enums stay contiguous");
_Static_assert(DF_WFMT_TETGEN == DF_FMT_MAX && DF_BRUSH_AFFINE == DF_BRUSH_TYPE_MAX &&
               DF_BP_RATIO == DF_BP_MAX && DF_ENERGY_POLYLINE == DF_ENERGY_MAX &&
               DF_CHANGE_SNAPSHOT == DF_CHANGE_MAX && DF_MOVE_FAILED == DF_MOVE_STATUS_MAX &&
               DF_SECTION_FACES == DF_SECTION_MAX && DF_ORIGIN_DEVICE == DF_ORIGIN_MAX,
               "the range-checked enums stay contiguous");
/* load_mesh `format` on the wire is 0..DF_FMT_MAX (core's DF_FMT_PLY_BINARY is write-only, not a
 * wire value). load_mesh `options`: unknown bits are refused with EPROTO_RESERVED (a server
 * without a bit answers that way too, so a client can tell and load without it); the same in
 * every chunk of an upload. */

/* ------------------------------------------------------------------------------ bodies */

typedef struct df_msg_hello {          /* client -> server, first message on a connection */
    uint16_t min_version;              /* oldest protocol version the client speaks, >= 1 */
    uint16_t max_version;              /* newest, >= min_version */
    uint32_t features;                 /* DF_FEAT_* bits the client can use (informative) */
    char client_name[DF_MAX_NAME_LEN + 1]; /* UTF-8, may be "" */
    /* optional trailing stream encoding request (PROTOCOL.md 4.2): absent in old clients' hello */
    uint8_t has_stream;                /* 1: the 10 trailing bytes are present (encode/decode) */
    uint8_t stream_encoding;           /* DF_STREAM_ENC_* bits; 0 = exact float32 */
    double error_bound;                /* QUANTIZED: absolute error E in mesh units, finite, in
                                        * [1e-30, 1e30]; else 0 */
} df_msg_hello;

typedef struct df_msg_hello_reply {
    uint16_t version;                  /* chosen version: max common version */
    uint16_t server_max_version;       /* newest version the server speaks */
    uint32_t features;                 /* DF_FEAT_* bits of this server */
    uint32_t max_frame_payload;        /* effective limits of this server (<= the constants) */
    uint32_t max_mesh_vertices;
    uint32_t max_mesh_elements;
    uint32_t max_pending_requests;
    uint32_t max_sessions;
    uint64_t max_mesh_bytes;
    uint64_t max_client_queue_bytes;   /* output queue bound; a client beyond it is dropped */
    uint8_t auth_required;             /* 1: requests other than hello/auth/ping get EPROTO_AUTH */
    char server_name[DF_MAX_NAME_LEN + 1]; /* e.g. "deformd 0.1" */
    /* optional trailer, present iff the hello had one: the stream encoding granted */
    uint8_t has_stream;
    uint8_t stream_encoding;           /* DF_STREAM_ENC_* bits */
    double error_bound;                /* as in df_msg_hello */
} df_msg_hello_reply;

typedef struct df_msg_auth {           /* AUTH request and reply (PROTOCOL.md 4.3) */
    uint16_t method;                   /* DF_AUTH_* (any u16 decodes; the server checks it) */
    uint32_t token_len;                /* <= DF_MAX_AUTH_TOKEN */
    const uint8_t *token;              /* points into the payload (decode) */
} df_msg_auth;

typedef struct df_msg_ping {
    uint32_t len;                      /* <= DF_MAX_PING_BYTES */
    const uint8_t *data;               /* points into the payload (decode) */
} df_msg_ping;

typedef struct df_msg_load_mesh {      /* one chunk of a mesh upload (or a path request) */
    uint8_t source;                    /* df_load_source */
    uint8_t format;                    /* df_mesh_format */
    char name[DF_MAX_NAME_LEN + 1];    /* session name, may be "" (server picks one) */
    char *path;                        /* PATH: NUL-terminated, 1..DF_MAX_PATH_LEN bytes; INLINE: NULL */
    uint64_t total_size;               /* INLINE: bytes of the whole upload, 1..DF_MAX_MESH_BYTES; PATH: 0 */
    uint64_t part2_offset;             /* TETGEN inline: byte where the .ele file starts
                                        * (0 < part2_offset < total_size); otherwise 0 */
    uint64_t offset;                   /* byte offset of this chunk in the upload; PATH: 0 */
    uint32_t data_len;                 /* bytes in this chunk; offset + data_len <= total_size */
    const uint8_t *data;               /* points into the payload (decode) */
    uint16_t options;                  /* DF_LOAD_OPT_* bits (0: the original layout and reply),
                                        * the same in every chunk (wire offset 2, after format) */
    char file_name[DF_MAX_NAME_LEN + 1]; /* DF_LOAD_OPT_EXT: the user's file name (base name, may be
                                        * "") for messages and the default session name; else "" */
} df_msg_load_mesh;

typedef struct df_msg_session_ref {    /* any request/event that names just a session */
    uint64_t session_id;               /* != 0 */
} df_msg_session_ref;

typedef struct df_msg_open_session {   /* open: by id, or by name when session_id == 0 */
    uint64_t session_id;
    char name[DF_MAX_NAME_LEN + 1];    /* used only when session_id == 0; then non-empty */
} df_msg_open_session;

typedef struct df_msg_subscribe {
    uint64_t session_id;               /* != 0 */
    uint32_t flags;                    /* DF_SUBSCRIBE_SNAPSHOT: send a dense snapshot first;
                                        * DF_SUBSCRIBE_FROM_VERSION: resync from from_version */
    uint64_t from_version;             /* the version the client holds (with FROM_VERSION only:
                                        * on the wire iff that flag is set; else 0) */
} df_msg_subscribe;

typedef struct df_msg_session_info {
    uint64_t session_id;               /* != 0 */
    uint64_t version;                  /* current version (0 right after load) */
    uint8_t kind;                      /* df_mesh_kind: 1 polyline, 2 triangle, 3 tet */
    uint8_t planar;                    /* 0/1 */
    uint16_t subscribers;              /* current subscriber count */
    uint32_t nv;                       /* vertices, 1..DF_MAX_MESH_VERTICES */
    uint32_t ne;                       /* elements, 0..DF_MAX_MESH_ELEMENTS */
    uint32_t undo_depth;               /* changes that undo can revert */
    uint32_t redo_depth;               /* changes that redo can re-apply */
    char name[DF_MAX_NAME_LEN + 1];
} df_msg_session_info;

typedef struct df_msg_load_report {   /* what the reader found (core df_mesh_report) */
    uint8_t format;                    /* 1..5: the format parsed */
    uint8_t index_base;                /* 0 or 1 */
    uint32_t input_polygons;           /* faces as written (before fan triangulation) */
    uint32_t polygons_triangulated;    /* of those, quads and n-gons */
    uint32_t dropped_elements;         /* lower-dimensional elements not kept (OBJ `l` lines beside
                                        * faces, MEDIT Edges in a tet mesh, skipped sections) */
    uint32_t duplicate_elements;       /* elements repeating an earlier element's vertex set */
    uint32_t degenerate_elements;
    uint32_t inverted_elements;
    uint32_t nonmanifold_edges;
    uint32_t nonmanifold_faces;
    uint32_t boundary_edges;
    uint32_t boundary_faces;
    uint32_t unused_vertices;          /* vertices no element uses */
} df_msg_load_report;

typedef struct df_msg_load_reply {     /* LOAD_MESH reply */
    df_msg_session_info info;
    uint8_t has_report;                /* 1 iff the request set DF_LOAD_OPT_EXT (report follows) */
    df_msg_load_report report;
} df_msg_load_reply;

typedef struct df_msg_shm_info {       /* STREAM_SHM reply: where this session's ring is */
    uint64_t session_id;               /* != 0 */
    uint64_t capacity;                 /* ring data bytes, >= DF_SHM_MIN_CAPACITY */
    uint32_t min_frame, max_frame;     /* event frames in [min, max] bytes go through the ring;
                                        * DF_FRAME_HEADER_SIZE <= min <= max <= capacity */
    char path[DF_MAX_PATH_LEN + 1];    /* absolute path of the ring file, non-empty */
} df_msg_shm_info;

typedef struct df_msg_shm_ref {        /* SHM_REF event: one event frame stored in the ring */
    uint64_t session_id;               /* != 0 */
    uint64_t position;                 /* stream position of the frame (shm_ring.h) */
    uint32_t length;                   /* whole frame bytes, >= DF_FRAME_HEADER_SIZE */
} df_msg_shm_ref;

typedef struct df_msg_session_list {
    uint32_t count;                    /* 0..DF_MAX_SESSIONS */
    df_msg_session_info *items;        /* count entries, malloc'd on decode */
} df_msg_session_list;

typedef struct df_msg_ack {            /* generic reply to a session change */
    uint64_t session_id;
    uint64_t version;                  /* session version after the request was applied */
} df_msg_ack;

typedef struct df_msg_brush {          /* brush stroke begin: every Kelvinlet parameter */
    uint64_t session_id;               /* != 0 */
    uint8_t type;                      /* df_brush_type */
    uint8_t dim;                       /* 2 (planar Kelvinlet, z untouched) or 3 */
    uint8_t falloff;                   /* multi-scale order 1..DF_MAX_FALLOFF */
    uint8_t integrator;                /* df_integrator, used when moving != 0 or steps > 1 */
    uint16_t steps;                    /* integration steps per update, 1..DF_MAX_BRUSH_STEPS */
    uint8_t moving;                    /* 0: centre stays at `center`; 1: centre follows the load */
    uint8_t has_mirror;                /* 0/1: also apply the brush mirrored across the plane */
    double radius;                     /* regularization radius eps, > 0, mesh units */
    double ratio;                      /* multi-scale radius ratio, > 1 (ignored if falloff 1) */
    double nu;                         /* Poisson ratio, not NaN, +-inf allowed (plain falloff) */
    double strength;                   /* load multiplier, finite (1 = as given) */
    double center[3];                  /* brush centre x0, finite */
    double move[3];                    /* GRAB: tip displacement at the centre, finite */
    double twist[3];                   /* TWIST: rotation vector (radians about its axis) */
    double scale;                      /* SCALE: centre dilation s, finite */
    double matrix[9];                  /* PINCH/AFFINE: centre gradient, row-major 3x3 */
    double mirror_point[3];            /* plane point, finite (when has_mirror) */
    double mirror_normal[3];           /* plane normal, finite, non-zero (when has_mirror) */
    uint32_t n_pinned;                 /* 0..DF_MAX_PINNED_POINTS */
    uint8_t pin_flags;                 /* n_pinned == 0: 0; else DF_PIN_* bits, 1..3 */
    double *pinned;                    /* n_pinned x 3 pinned positions, malloc'd on decode */
    uint16_t use_session;              /* DF_BS_* bits: fields the server takes from the session
                                        * brush (brush_state) instead of this message; optional
                                        * trailing u16 on the wire, absent = 0 */
    uint8_t use_session_field;         /* decode: 1 when the body carried the u16 (even 0);
                                        * encode: write it when use_session != 0 or this is 1.
                                        * 0 with use_session 0 is the original 253 + 24n layout */
    uint32_t options;                  /* DF_WORK_OPT_* (PROGRESS: WORK_PROGRESS of the pinned
                                        * points' LU for this stroke); optional trailing u32
                                        * after use_session (which is then always written) */
    uint8_t options_field;             /* as use_session_field, for `options` */
    uint8_t surface;                   /* 1: surface-aware (attenuated by the distance along the
                                        * mesh from the centre), 0: plain; optional trailing u8
                                        * after options (which are then sent too), absent = 0 */
} df_msg_brush;

typedef struct df_msg_brush_update {   /* cumulative load since the stroke began */
    uint64_t session_id;               /* != 0 */
    double move[3];                    /* same meaning and units as in df_msg_brush, finite */
    double twist[3];
    double scale;
    double matrix[9];
} df_msg_brush_update;

typedef struct df_msg_brush_param {    /* HID knobs: change one parameter of this client's brush */
    uint64_t session_id;               /* != 0 */
    uint8_t param;                     /* df_brush_param_id */
    double value;                      /* range per df_brush_param_id */
} df_msg_brush_param;

/* The session brush (PROTOCOL.md 4.14a), as in brush_state / brush_state_set. Ranges (checked
 * for the fields a mask selects): type df_brush_type, falloff 1..DF_MAX_FALLOFF, integrator
 * df_integrator, steps 1..DF_MAX_BRUSH_STEPS, has_mirror 0/1, radius finite > 0, nu not NaN,
 * strength finite, ratio finite > 1, mirror point/normal finite (normal non-zero if has_mirror). */
typedef struct df_msg_brush_values {
    uint8_t type, falloff, integrator, has_mirror;
    uint16_t steps;
    double radius, nu, strength, ratio;
    double mirror_point[3], mirror_normal[3];
} df_msg_brush_values;

typedef struct df_msg_brush_state_set { /* set some fields of the session brush */
    uint64_t session_id;               /* != 0 */
    uint16_t mask;                     /* DF_BS_* bits, != 0: the fields of `v` to set (the others
                                        * are carried but ignored, any value) */
    df_msg_brush_values v;
} df_msg_brush_state_set;

typedef struct df_msg_brush_state {    /* the session brush: reply to get/set, and the event */
    uint64_t session_id;               /* != 0 */
    uint64_t seq;                      /* changes of this session's brush so far (0: defaults) */
    uint16_t changed;                  /* DF_BS_* bits the change set (get reply: 0) */
    uint8_t origin_kind;               /* df_origin_kind of who made the last change */
    uint64_t origin_id;                /* connection id / device id (NONE: 0) */
    char origin_name[DF_MAX_NAME_LEN + 1]; /* client HELLO name / device name, may be "" */
    df_msg_brush_values v;             /* every field, all valid */
} df_msg_brush_state;

typedef struct df_msg_brush_cursor {   /* where an origin's brush points (rate-limited event) */
    uint64_t session_id;               /* != 0 */
    uint8_t origin_kind;               /* df_origin_kind */
    uint64_t origin_id;
    uint8_t flags;                     /* DF_CURSOR_* bits: in range, stroke active */
    double center[3];                  /* brush centre in mesh coordinates, finite */
    double radius;                     /* finite, > 0, mesh units */
} df_msg_brush_cursor;

typedef struct df_msg_affine_set {     /* A V_t = b for every vertex t of the set (paper eq. 2c) */
    uint8_t rows;                      /* 1..3 constraint rows */
    double A[9];                       /* rows x 3, row-major; unused rows 0 */
    double b[3];                       /* rows entries; unused 0 */
    uint32_t n_indices;                /* 1..DF_MAX_HANDLES */
    int32_t *indices;                  /* vertex indices, malloc'd on decode */
} df_msg_affine_set;

typedef struct df_msg_handles {        /* define the session's handle set (replaces any previous);
                                        * start from df_msg_handles_defaults */
    uint64_t session_id;               /* != 0 */
    uint8_t energy;                    /* df_energy */
    uint8_t area_weighting;            /* 0: a_i = 1 (paper code); 1: barycentric vertex measure */
    uint8_t accelerate;                /* 0: plain ADMM; 1: Anderson-accelerated */
    uint8_t anderson_m;                /* Anderson history, 1..DF_MAX_ANDERSON */
    double w;                          /* SC-L1 locality weight, finite, >= 0 */
    double s;                          /* SC-L1 threshold, finite, > 0, mesh units */
    double rho;                        /* ADMM penalty, finite, > 0 (engine: > w max(a_i) / s) */
    double tol;                        /* residual tolerance, finite, >= 0 */
    double youngs;                     /* NEOHOOKEAN Young's modulus E in Pa, finite, > 0 */
    double poisson;                    /* NEOHOOKEAN Poisson ratio, in (-1, 0.5) */
    double strain_min;                 /* CLOTH stretch limits: 0 < strain_min <= 1 */
    double strain_max;                 /*   1 <= strain_max, finite */
    double bending;                    /* CLOTH bending stiffness, finite, >= 0 */
    uint32_t max_iters;                /* default budget, 1..DF_MAX_MOVE_ITERS */
    uint32_t n_handles;                /* 1..DF_MAX_HANDLES */
    int32_t *handles;                  /* handle vertex indices, malloc'd on decode */
    uint32_t n_affine;                 /* 0..DF_MAX_AFFINE_SETS */
    df_msg_affine_set *affine;         /* malloc'd on decode */
    uint32_t options;                  /* DF_WORK_OPT_* (optional trailing u32 on the wire) */
    uint8_t options_field;             /* 1: the body carries `options` (decode: it was present;
                                        * encode: write it even when 0); 0: written only when
                                        * options != 0, else the original layout */
} df_msg_handles;

typedef struct df_msg_handle_move {    /* move the handles; supersedes a running move */
    uint64_t session_id;               /* != 0 */
    uint32_t max_iters;                /* 0: the handle set's max_iters; else 1..DF_MAX_MOVE_ITERS */
    uint32_t max_ms;                   /* wall-clock budget in ms, 0 = none */
    uint32_t progress_every;           /* progress event every N iterations, 0 = final only */
    uint32_t n_targets;                /* must equal the handle set's n_handles (server checks) */
    double *targets;                   /* n_targets x 3 target positions, finite, malloc'd on decode */
    uint32_t options;                  /* DF_WORK_OPT_* (optional trailing u32) */
    uint8_t options_field;             /* as in df_msg_handles */
} df_msg_handle_move;

typedef struct df_msg_move_result {    /* final reply of a handle move */
    uint64_t session_id;
    uint64_t version;                  /* version of the last iterate published */
    uint8_t status;                    /* df_move_status (not RUNNING) */
    uint32_t iterations;               /* ADMM iterations run */
    double objective;                  /* final energy, finite */
    double residual;                   /* stop residual (admm.h DF_ADMM_RESIDUAL), finite, >= 0 */
    double elapsed_ms;                 /* solve wall time, finite, >= 0 */
} df_msg_move_result;

typedef struct df_msg_get_mesh {
    uint64_t session_id;               /* != 0 */
    uint32_t flags;                    /* DF_GET_MESH_REST / DF_GET_MESH_BASE: extra sections */
} df_msg_get_mesh;

typedef struct df_msg_mesh_chunk {     /* one chunk of a get-mesh reply */
    uint64_t session_id;
    uint64_t version;                  /* version the positions belong to */
    uint8_t kind;                      /* df_mesh_kind 1..3 */
    uint8_t planar;                    /* 0/1 */
    uint8_t section;                   /* df_mesh_section */
    uint32_t nv, ne, nf;               /* mesh counts (same in every chunk) */
    uint32_t offset;                   /* first row of the section in this chunk */
    uint32_t count;                    /* rows in this chunk; offset + count <= section rows */
    float *xyz;                        /* POSITIONS/BASE/REST: count x 3, malloc'd on decode */
    int32_t *idx;                      /* ELEMENTS: count x elem_size; FACES: count x 3; each
                                        * index < nv; malloc'd on decode */
} df_msg_mesh_chunk;

typedef struct df_msg_snapshot_req {
    uint64_t session_id;               /* != 0 */
    uint64_t version;                  /* 0: current; else a retained version (ENOTFOUND if not) */
} df_msg_snapshot_req;

/* One chunk of one session version. Values are float32 displacements u_i = x_i - X_i from the
 * session's BASE positions X (load-time, never change); a client computes x_i = X_i + u_i in
 * float32. A frame lists every vertex whose u changed since base_version (dense: all of them). */
typedef struct df_msg_disp {
    uint64_t session_id;               /* != 0 */
    uint64_t version;                  /* the version this change produces, > base_version */
    uint64_t base_version;             /* version the change applies to (SNAPSHOT: 0) */
    uint8_t kind;                      /* df_change_kind */
    uint8_t encoding;                  /* df_disp_encoding */
    uint32_t nv;                       /* mesh vertex count, 1..DF_MAX_MESH_VERTICES */
    uint32_t total;                    /* rows of the whole (unchunked) message: DENSE == nv,
                                        * SPARSE <= nv */
    uint32_t offset;                   /* first row of this chunk, offset + count <= total */
    uint32_t count;                    /* rows in this chunk */
    int32_t *idx;                      /* SPARSE: count vertex indices (< nv, strictly
                                        * increasing within a chunk); DENSE: NULL. malloc'd */
    float *xyz;                        /* count x 3 displacements, finite, malloc'd on decode */
} df_msg_disp;

typedef struct df_msg_progress {       /* one ADMM iterate of a handle move (a session version) */
    uint8_t status;                    /* df_move_status; != RUNNING on the final frame */
    uint8_t final;                     /* 1 on the last iterate of this move */
    uint32_t iteration;                /* 1-based iteration count */
    double objective;                  /* finite */
    double residual;                   /* finite, >= 0 */
    double elapsed_ms;                 /* finite, >= 0 */
    df_msg_disp disp;                  /* the iterate (kind DF_CHANGE_HANDLE_MOVE) */
} df_msg_progress;

typedef struct df_msg_work_progress {  /* WORK_PROGRESS event (PROTOCOL.md 4.37), 36 bytes */
    uint64_t session_id;               /* the request's session; 0 while a load has none */
    uint8_t stage;                     /* df_work_stage; any value >= 1 decodes (newer stages) */
    uint8_t final;                     /* 0/1: the last event of this stage for this request */
    uint64_t done;                     /* units of the stage done (bytes, steps, iterations) */
    uint64_t total;                    /* units in all, >= done; 0 when unknown */
    double elapsed_ms;                 /* since the stage began, finite, >= 0 */
} df_msg_work_progress;

typedef struct df_msg_stats_req {
    uint64_t session_id;               /* 0: daemon-wide stats; else that session's */
} df_msg_stats_req;

typedef struct df_msg_stat {
    char key[DF_MAX_STATS_KEY_LEN + 1];/* non-empty [a-z0-9_.] e.g. "cache.kelvinlet_lu.hits" */
    double value;                      /* finite */
} df_msg_stat;

typedef struct df_msg_stats {
    uint32_t count;                    /* 0..DF_MAX_STATS_ENTRIES */
    df_msg_stat *items;                /* malloc'd on decode */
} df_msg_stats;

/* the bodies of the device, access, peer and stream-encoding messages (PROTOCOL.md 4.30-4.41) */
#include "proto/messages_ext.h"

/* ------------------------------------------------------------------------------ functions */
#define DF_MSG_CODEC(T)                                                                \
    int df_msg_##T##_encode(const df_msg_##T *m, df_buf *out, df_error *err);          \
    int df_msg_##T##_decode(const uint8_t *p, size_t n, df_msg_##T *m, df_error *err);

DF_MSG_CODEC(hello)
DF_MSG_CODEC(hello_reply)
DF_MSG_CODEC(auth)
DF_MSG_CODEC(ping)
DF_MSG_CODEC(load_mesh)
DF_MSG_CODEC(session_ref)
DF_MSG_CODEC(open_session)
DF_MSG_CODEC(subscribe)
DF_MSG_CODEC(session_info)
DF_MSG_CODEC(load_reply)
DF_MSG_CODEC(session_list)
DF_MSG_CODEC(ack)
DF_MSG_CODEC(brush)
DF_MSG_CODEC(brush_update)
DF_MSG_CODEC(brush_param)
DF_MSG_CODEC(handles)
DF_MSG_CODEC(handle_move)
DF_MSG_CODEC(move_result)
DF_MSG_CODEC(get_mesh)
DF_MSG_CODEC(mesh_chunk)
DF_MSG_CODEC(snapshot_req)
DF_MSG_CODEC(disp)
DF_MSG_CODEC(progress)
DF_MSG_CODEC(stats_req)
DF_MSG_CODEC(stats)
DF_MSG_CODEC(shm_info)
DF_MSG_CODEC(shm_ref)
DF_MSG_CODEC(brush_state_set)
DF_MSG_CODEC(brush_state)
DF_MSG_CODEC(brush_cursor)
DF_MSG_CODEC(device_info)
DF_MSG_CODEC(device_list)
DF_MSG_CODEC(device_bind)
DF_MSG_CODEC(device_view)
DF_MSG_CODEC(session_access)
DF_MSG_CODEC(join)
DF_MSG_CODEC(access_info)
DF_MSG_CODEC(work_progress)
DF_MSG_CODEC(peer_info)
DF_MSG_CODEC(peer_list)
DF_MSG_CODEC(qdisp)
DF_MSG_CODEC(zframe)
#undef DF_MSG_CODEC

/* Checks the fields of `v` selected by `mask` (DF_BS_* bits) against the ranges of
 * df_msg_brush_values; `msg` names the message in errors. DF_OK, DF_EINVAL naming the field, or
 * DF_EPROTO_RESERVED for a bit outside DF_BS_ALL. Pure. */
int df_msg_brush_values_check(const df_msg_brush_values *v, unsigned mask, const char *msg,
                              df_error *err);

/* Fills `v` with the brush defaults (DF_WIRE_BRUSH_DEFAULTS; mirror off, normal (1,0,0)). */
void df_msg_brush_values_defaults(df_msg_brush_values *v);

/* Fills `m` with the defaults clients should start from (DF_WIRE_BRUSH_DEFAULTS of
 * proto/wire_schema.h): GRAB, dim 3, falloff 1, ratio 1.1, radius 1, nu 0.5, strength 1, Euler
 * 1 step, stationary, no mirror (normal (1,0,0)), loads 0, no pinned points; session_id 0. */
void df_msg_brush_defaults(df_msg_brush *m);

/* Fills `m` with the solver's defaults for `energy` (df_energy; 0 or unknown -> ARAP), from
 * core/admm/admm_defaults.h (the one place of them: w 1e-4, s 0.01, rho 0, tol 1e-11,
 * max_iters 500, E 1e7 Pa, Poisson 0.45, strain [0.9, 1.1], bending 1e-3, a_i = 1, no
 * acceleration, Anderson m 5; NEOHOOKEAN: w 500; rho 0 = adaptive). No handles (set n_handles/handles),
 * session_id 0. */
void df_msg_handles_defaults(df_msg_handles *m, uint8_t energy);

/* Frees what the decoder allocated and zeroes the pointer/count fields; NULL-safe. */
void df_msg_load_mesh_free(df_msg_load_mesh *m);
void df_msg_session_list_free(df_msg_session_list *m);
void df_msg_brush_free(df_msg_brush *m);
void df_msg_handles_free(df_msg_handles *m);
void df_msg_handle_move_free(df_msg_handle_move *m);
void df_msg_mesh_chunk_free(df_msg_mesh_chunk *m);
void df_msg_disp_free(df_msg_disp *m);
void df_msg_progress_free(df_msg_progress *m);
void df_msg_stats_free(df_msg_stats *m);
void df_msg_device_list_free(df_msg_device_list *m);
void df_msg_peer_list_free(df_msg_peer_list *m);
void df_msg_qdisp_free(df_msg_qdisp *m);

/* Checks a hello / hello_reply stream-encoding trailer (PROTOCOL.md 4.2): without `has`, enc and
 * e must be 0; with it, enc only DF_STREAM_ENC_* bits, e in [DF_STREAM_ERROR_LO,
 * DF_STREAM_ERROR_HI] with QUANTIZED and 0 without. DF_OK or DF_EINVAL naming the field (`msg`
 * names the message). Pure. */
int df_msg_stream_enc_check(uint8_t has, uint8_t enc, double e, const char *msg, df_error *err);

/* Empty bodies (list sessions request, auth success reply): DF_OK for n == 0, else
 * DF_EPROTO_TRAILING. */
int df_msg_empty_decode(const uint8_t *p, size_t n, df_error *err);

/* Error body: i32 code (a valid wire code), u16 length, message bytes (<= DF_MAX_ERROR_MSG_LEN,
 * no NUL). Encode writes e->code and e->msg (truncated to the limit); decode fills `*out`. */
int df_msg_error_encode(const df_error *e, df_buf *out, df_error *err);
int df_msg_error_decode(const uint8_t *p, size_t n, df_error *out, df_error *err);

/* Convenience for servers: appends a whole error frame carrying `code` and the printf-style
 * message: an error reply (type = the request's type, even one unknown to this build; flags
 * REPLY|ERROR) when request_id != 0, else a connection-level ERROR event (type DF_MSG_ERROR,
 * flags ERROR, request id 0). Type 0 becomes DF_MSG_ERROR. DF_OK or DF_ENOMEM. */
int df_msg_error_frame(df_buf *out, uint16_t type, uint64_t request_id, int code,
                       df_error *err, const char *fmt, ...) __attribute__((format(printf, 6, 7)));

/* Stream helpers.
 * df_msg_disp_row_bytes: wire bytes per row (12 dense, 16 sparse; 0 for a bad encoding).
 * df_msg_disp_rows_per_chunk: rows that fit in a payload of `max_payload` bytes (>= 1).
 * df_msg_disp_choose: DF_DISP_SPARSE when `changed` rows are cheaper sparse than all `nv`
 * dense, else DF_DISP_DENSE. */
size_t df_msg_disp_row_bytes(uint8_t encoding);
uint32_t df_msg_disp_rows_per_chunk(uint8_t encoding, size_t max_payload);
uint8_t df_msg_disp_choose(uint32_t changed, uint32_t nv);

/* Generic decode for tools, fuzzers and logging: decodes the body selected by (type, flags)
 * as listed on df_msg_type. `which` tells the caller which member of the union is valid. */
typedef enum df_body_kind {
    DF_BODY_EMPTY = 0, DF_BODY_ERROR, DF_BODY_HELLO, DF_BODY_HELLO_REPLY, DF_BODY_AUTH,
    DF_BODY_PING, DF_BODY_LOAD_MESH, DF_BODY_SESSION_REF, DF_BODY_OPEN_SESSION,
    DF_BODY_SUBSCRIBE, DF_BODY_SESSION_INFO, DF_BODY_SESSION_LIST, DF_BODY_ACK, DF_BODY_BRUSH,
    DF_BODY_BRUSH_UPDATE, DF_BODY_BRUSH_PARAM, DF_BODY_HANDLES, DF_BODY_HANDLE_MOVE,
    DF_BODY_MOVE_RESULT, DF_BODY_GET_MESH, DF_BODY_MESH_CHUNK, DF_BODY_SNAPSHOT_REQ,
    DF_BODY_DISP, DF_BODY_PROGRESS, DF_BODY_STATS_REQ, DF_BODY_STATS, DF_BODY_SHM_INFO,
    DF_BODY_SHM_REF, DF_BODY_LOAD_REPLY, DF_BODY_BRUSH_STATE_SET, DF_BODY_BRUSH_STATE,
    DF_BODY_BRUSH_CURSOR,
    /* devices (HID) */
    DF_BODY_DEVICE_INFO, DF_BODY_DEVICE_LIST, DF_BODY_DEVICE_BIND, DF_BODY_DEVICE_VIEW,
    /* per-session access */
    DF_BODY_SESSION_ACCESS, DF_BODY_JOIN, DF_BODY_ACCESS_INFO,
    DF_BODY_WORK_PROGRESS,
    /* session peers */
    DF_BODY_PEER_LIST,
    /* negotiated stream encodings */
    DF_BODY_QDISP, DF_BODY_ZFRAME
} df_body_kind;

typedef struct df_msg_any {
    df_body_kind which;
    union {
        df_error error;
        df_msg_hello hello;
        df_msg_hello_reply hello_reply;
        df_msg_auth auth;
        df_msg_ping ping;
        df_msg_load_mesh load_mesh;
        df_msg_session_ref session_ref;
        df_msg_open_session open_session;
        df_msg_subscribe subscribe;
        df_msg_session_info session_info;
        df_msg_session_list session_list;
        df_msg_ack ack;
        df_msg_brush brush;
        df_msg_brush_update brush_update;
        df_msg_brush_param brush_param;
        df_msg_handles handles;
        df_msg_handle_move handle_move;
        df_msg_move_result move_result;
        df_msg_get_mesh get_mesh;
        df_msg_mesh_chunk mesh_chunk;
        df_msg_snapshot_req snapshot_req;
        df_msg_disp disp;
        df_msg_progress progress;
        df_msg_stats_req stats_req;
        df_msg_stats stats;
        df_msg_shm_info shm_info;
        df_msg_shm_ref shm_ref;
        df_msg_load_reply load_reply;
        df_msg_brush_state_set brush_state_set;
        df_msg_brush_state brush_state;
        df_msg_brush_cursor brush_cursor;
        df_msg_device_info device_info;
        df_msg_device_list device_list;
        df_msg_device_bind device_bind;
        df_msg_device_view device_view;
        df_msg_session_access session_access;
        df_msg_join join;
        df_msg_access_info access_info;
        df_msg_work_progress work_progress;
        df_msg_peer_list peer_list;
        df_msg_qdisp qdisp;
        df_msg_zframe zframe;
    } u;
} df_msg_any;

/* Body kind of (type, flags): DF_FLAG_ERROR -> DF_BODY_ERROR; DF_FLAG_REPLY -> the reply body;
 * DF_FLAG_EVENT -> the event body; none -> the request body. DF_EPROTO_BADTYPE when the
 * combination is not defined (e.g. a request of type DF_MSG_DISPLACEMENT). */
int df_msg_body_kind(uint16_t type, uint16_t flags, df_body_kind *out, df_error *err);

/* Decodes payload `p` of `n` bytes for (type, flags) into `*m` (see df_msg_body_kind).
 * Release with df_msg_any_free. */
int df_msg_any_decode(uint16_t type, uint16_t flags, const uint8_t *p, size_t n, df_msg_any *m,
                      df_error *err);
void df_msg_any_free(df_msg_any *m);

/* Encodes the body held in `*m` (selected by m->which) by appending it to `out`; the inverse of
 * df_msg_any_decode. Returns DF_OK, the body encoder's error, or DF_EINTERNAL for an unknown kind. */
int df_msg_any_encode(const df_msg_any *m, df_buf *out, df_error *err);

#endif
