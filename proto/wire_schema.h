/* wire_schema.h — the one source of truth of the wire protocol's numbers: message types (with
 * their request / reply / event bodies), flags, feature bits, every wire enum, the limits and the
 * brush defaults. Header-only, no includes, plain macros: proto/messages.h and proto/frame.h build
 * their C enums and constants from it; nothing else may restate a value.
 *
 * Checked against, by tests/integration/test_schema.py (which compiles a dump of this header):
 *  - client/python/deformd_client/schema.py (IntEnum / IntFlag classes, limits, defaults),
 *  - the tables of proto/PROTOCOL.md (section 3 types and bodies, the enum and bit columns of
 *    section 4, section 8 limits),
 *  - core/admm/admm_defaults.h (the ADMM defaults, owned by core) against the Python defaults.
 * Wire enums own their numbering: the one bounds-checked mapping of each to core's enums is in
 * proto/wire_core_map.h. To add a value: add it here, to schema.py and to PROTOCOL.md; the test
 * names whatever is missing.
 *
 * List macros take a callback X; each entry is one X(...) call:
 *  DF_WIRE_MSG_TYPES(X):  X(NAME, value, lower_name, request_body, reply_body, event_body); a
 *                         body is a DF_BODY_* suffix (messages.h df_body_kind) or NONE.
 *  DF_WIRE_<ENUM>(X):     X(NAME, value) for each enum below (C name DF_<PREFIX>_NAME).
 *  DF_WIRE_LIMITS(X):     X(DF_MAX_...) for every limit #define below.
 *  DF_WIRE_BRUSH_DEFAULTS(X): X(field, value) of df_msg_brush_defaults / Python Brush(). */
#ifndef DF_PROTO_WIRE_SCHEMA_H
#define DF_PROTO_WIRE_SCHEMA_H

/* ------------------------------------------------------------------------ frame (frame.h) */
#define DF_FRAME_MAGIC 0x444D4644u       /* bytes "DFMD" read as a little-endian u32 */
#define DF_PROTO_VERSION 1u
#define DF_FRAME_HEADER_SIZE 24u

#define DF_WIRE_FLAGS(X)                                                                     \
    X(REPLY, 1u << 0) /* answers the request with the same request_id */                     \
    X(EVENT, 1u << 1) /* server-initiated (stream frames, progress) */                       \
    X(ERROR, 1u << 2) /* payload is an error body (code + message) */                        \
    X(MORE, 1u << 3)  /* more chunks of the same message follow */

/* ---------------------------------------------------------------- limits (reported in hello) */
#define DF_MAX_FRAME_PAYLOAD (64u << 20)      /* 64 MiB: larger messages are chunked */
#define DF_MAX_MESH_VERTICES (8u << 20)       /* 8,388,608 vertices per mesh */
#define DF_MAX_MESH_ELEMENTS (32u << 20)      /* 33,554,432 elements per mesh */
#define DF_MAX_MESH_BYTES (1ull << 30)        /* 1 GiB: largest inline mesh upload (all chunks) */
#define DF_MAX_PENDING_REQUESTS 64u           /* unanswered requests per client; more -> EBUSY */
#define DF_MAX_SESSIONS 1024u                 /* sessions per daemon (and per list reply) */
#define DF_MAX_NAME_LEN 255u                  /* bytes of a session / client / server name */
#define DF_MAX_PATH_LEN 4095u                 /* bytes of a server-side path */
#define DF_MAX_ERROR_MSG_LEN 255u             /* bytes of error message on the wire */
#define DF_MAX_AUTH_TOKEN 4096u               /* bytes of an auth token */
#define DF_MAX_PING_BYTES 65536u              /* bytes echoed by ping */
#define DF_MAX_PINNED_POINTS 2048u            /* pinned points of one brush stroke */
#define DF_MAX_BRUSH_STEPS 1024u              /* integrator steps of one brush update */
#define DF_MAX_FALLOFF 8u                     /* falloff order: 1 single, 2 bi, 3 tri-scale, .. 8 */
#define DF_MAX_HANDLES (1u << 20)             /* handle vertices of one handle set */
#define DF_MAX_AFFINE_SETS 64u                /* affine constraint sets of one handle set */
#define DF_MAX_ANDERSON 20u                   /* Anderson history length of accelerated ADMM */
#define DF_MAX_MOVE_ITERS 1000000u            /* ADMM iteration budget of one move */
#define DF_MAX_STATS_ENTRIES 1024u            /* key/value pairs in one stats reply */
#define DF_MAX_STATS_KEY_LEN 63u              /* bytes of a stats key */
#define DF_STREAM_CHUNK_BYTES (16u << 20)     /* recommended payload bound of a stream chunk */
/* devices (HID, issue 11) */
#define DF_MAX_DEVICES 256u                   /* devices in a device_list (and per daemon) */
/* session peers (SESSION_PEERS, PROTOCOL.md 4.38) */
#define DF_MAX_PEERS 4096u                    /* rows of a peer_list */

#define DF_WIRE_LIMITS(X)                                                                    \
    X(DF_MAX_FRAME_PAYLOAD) X(DF_MAX_MESH_VERTICES) X(DF_MAX_MESH_ELEMENTS)                  \
    X(DF_MAX_MESH_BYTES) X(DF_MAX_PENDING_REQUESTS) X(DF_MAX_SESSIONS) X(DF_MAX_NAME_LEN)    \
    X(DF_MAX_PATH_LEN) X(DF_MAX_ERROR_MSG_LEN) X(DF_MAX_AUTH_TOKEN) X(DF_MAX_PING_BYTES)     \
    X(DF_MAX_PINNED_POINTS) X(DF_MAX_BRUSH_STEPS) X(DF_MAX_FALLOFF) X(DF_MAX_HANDLES)        \
    X(DF_MAX_AFFINE_SETS) X(DF_MAX_ANDERSON) X(DF_MAX_MOVE_ITERS) X(DF_MAX_STATS_ENTRIES)    \
    X(DF_MAX_STATS_KEY_LEN) X(DF_STREAM_CHUNK_BYTES)                                      \
    X(DF_MAX_DEVICES)                                                                        \
    X(DF_MAX_PEERS)

/* ------------------------------------------------- AUTH HMAC-SHA256 exchange (PROTOCOL.md 4.3) */
#define DF_AUTH_NONCE_BYTES 32u             /* client and server nonces */
#define DF_AUTH_MAC_BYTES 32u               /* HMAC-SHA256 output */
#define DF_AUTH_CONTEXT_CLIENT "deformd-auth-v1 client" /* ends the client's MAC input */
#define DF_AUTH_CONTEXT_SERVER "deformd-auth-v1 server" /* ends the server's MAC input */

/* ------------------------------------------------ session join key (PROTOCOL.md 4.35, 4.36) */
#define DF_JOIN_KEY_BYTES 32u               /* a session's join key: 32 random bytes */

/* ------------------------------------------- shared-memory ring file (PROTOCOL.md 6.1, shm_ring.h) */
#define DF_SHM_MAGIC "DFSHMRG1"             /* 8 bytes at offset 0 */
#define DF_SHM_HEADER_BYTES 4096u           /* data starts here (one page) */
#define DF_SHM_MIN_CAPACITY 4096u           /* smallest ring a server may make */
#define DF_SHM_MAX_CAPACITY (4ull << 30)    /* largest (4 GiB) */

/* ----------------------------------------------------------------------------- message types
 * Requests are sent by clients (flags 0, or MORE on all but the last chunk of a load). The reply
 * reuses the request's type with REPLY (| ERROR with an error body). Events carry EVENT. */
#define DF_WIRE_MSG_TYPES(X)                                                                 \
    X(HELLO, 0x0001, hello, HELLO, HELLO_REPLY, NONE)                                        \
    X(AUTH, 0x0002, auth, AUTH, AUTH, NONE) /* reply: the next token (4.3), or an error */   \
    X(PING, 0x0003, ping, PING, PING, NONE)  /* reply: the same bytes */                     \
    X(LOAD_MESH, 0x0010, load_mesh, LOAD_MESH, LOAD_REPLY, NONE) /* chunked upload */        \
    X(LIST_SESSIONS, 0x0011, list_sessions, EMPTY, SESSION_LIST, NONE)                       \
    X(OPEN_SESSION, 0x0012, open_session, OPEN_SESSION, SESSION_INFO, NONE)                  \
    X(CLOSE_SESSION, 0x0013, close_session, SESSION_REF, ACK, NONE)                          \
    X(SUBSCRIBE, 0x0014, subscribe, SUBSCRIBE, SESSION_INFO, NONE)                           \
    X(UNSUBSCRIBE, 0x0015, unsubscribe, SESSION_REF, ACK, NONE)                              \
    X(STREAM_SHM, 0x0016, stream_shm, SESSION_REF, SHM_INFO, NONE)                           \
    /* per-session access (PROTOCOL.md 4.34..4.36) */                                         \
    X(SESSION_ACCESS, 0x0017, session_access, SESSION_ACCESS, ACCESS_INFO, NONE)             \
    X(JOIN, 0x0018, join, JOIN, ACCESS_INFO, NONE)                                           \
    X(SESSION_PEERS, 0x0019, session_peers, SESSION_REF, PEER_LIST, NONE) /* 4.38 */         \
    X(BRUSH_BEGIN, 0x0020, brush_begin, BRUSH, ACK, NONE)                                    \
    X(BRUSH_UPDATE, 0x0021, brush_update, BRUSH_UPDATE, ACK, NONE)                           \
    X(BRUSH_END, 0x0022, brush_end, SESSION_REF, ACK, NONE)                                  \
    X(BRUSH_CANCEL, 0x0023, brush_cancel, SESSION_REF, ACK, NONE)                            \
    X(SET_BRUSH_PARAM, 0x0024, set_brush_param, BRUSH_PARAM, ACK, NONE)                      \
    X(BRUSH_STATE_GET, 0x0025, brush_state_get, SESSION_REF, BRUSH_STATE, NONE)              \
    X(BRUSH_STATE_SET, 0x0026, brush_state_set, BRUSH_STATE_SET, BRUSH_STATE, NONE)          \
    X(HANDLES_SET, 0x0030, handles_set, HANDLES, ACK, NONE)                                  \
    X(HANDLES_MOVE, 0x0031, handles_move, HANDLE_MOVE, MOVE_RESULT, NONE) /* at the end */   \
    X(RESET_REST, 0x0032, reset_rest, SESSION_REF, ACK, NONE)                                \
    X(UNDO, 0x0033, undo, SESSION_REF, ACK, NONE)                                            \
    X(REDO, 0x0034, redo, SESSION_REF, ACK, NONE)                                            \
    X(HANDLES_GET, 0x0035, handles_get, SESSION_REF, HANDLES, NONE) /* ENOTFOUND if none */  \
    X(GET_MESH, 0x0040, get_mesh, GET_MESH, MESH_CHUNK, NONE)        /* chunked reply */     \
    X(SNAPSHOT, 0x0041, snapshot, SNAPSHOT_REQ, DISP, NONE)          /* chunked, dense */    \
    X(STATS, 0x0042, stats, STATS_REQ, STATS, NONE)                                          \
    /* devices (HID): PROTOCOL.md 4.30..4.33 */                                               \
    X(DEVICES_LIST, 0x0050, devices_list, EMPTY, DEVICE_LIST, NONE)                          \
    X(DEVICE_BIND, 0x0051, device_bind, DEVICE_BIND, EMPTY, NONE)                            \
    X(DEVICE_VIEW, 0x0052, device_view, DEVICE_VIEW, EMPTY, NONE)                            \
    X(DISPLACEMENT, 0x0080, displacement, NONE, NONE, DISP)     /* one session version */    \
    X(PROGRESS, 0x0081, progress, NONE, NONE, PROGRESS)         /* one ADMM iterate */       \
    X(SESSION_CLOSED, 0x0082, session_closed, NONE, NONE, SESSION_REF)                       \
    X(SHM_REF, 0x0083, shm_ref, NONE, NONE, SHM_REF) /* next event frame is in the ring */   \
    X(BRUSH_STATE, 0x0084, brush_state, NONE, NONE, BRUSH_STATE) /* session brush changed */ \
    X(BRUSH_CURSOR, 0x0085, brush_cursor, NONE, NONE, BRUSH_CURSOR) /* rate-limited */       \
    X(DEVICE_STATE, 0x0086, device_state, NONE, NONE, DEVICE_INFO) /* a device changed */    \
    X(WORK_PROGRESS, 0x0087, work_progress, NONE, NONE, WORK_PROGRESS) /* opt-in, 4.37 */    \
    /* negotiated stream encodings (hello stream_encoding, PROTOCOL.md 4.40, 4.41) */           \
    X(QDISP, 0x0088, qdisp, NONE, NONE, QDISP)      /* one version, quantized delta */       \
    X(ZFRAME, 0x0089, zframe, NONE, NONE, ZFRAME)   /* a zstd-compressed event frame */      \
    X(ERROR, 0x00FF, error, NONE, NONE, NONE) /* error body not tied to a request type */

/* ------------------------------------------------------------------------------ feature bits
 * hello_reply `features`. Only what this build implements: a server sets a bit only when the
 * feature works on that connection; any unknown bit is refused by hello_reply decoders. The
 * features of a client's hello are informative and never checked (clients built before HID
 * announce 0xBF or 0xFF). Bit 6 is HID: it was reserved (withdrawn) until the HID subsystem
 * existed, and decoders always accepted it, so older clients work with a daemon that sets it. */
#define DF_WIRE_FEATURES(X)                                                                  \
    X(KELVINLET, 1u << 0)     /* brush messages supported */                                 \
    X(ADMM, 1u << 1)          /* handle set / move supported */                              \
    X(PATH_LOAD, 1u << 2)     /* load mesh from a server-side path allowed by config */      \
    X(AUTH, 1u << 3)          /* auth is implemented (and may be required) */                \
    X(SPARSE_STREAM, 1u << 4) /* server sends sparse displacement frames */                  \
    X(TCP, 1u << 5)           /* the daemon also listens on TCP */                           \
    X(HID, 1u << 6)           /* the HID device subsystem runs (DEVICES_LIST ...) */         \
    X(SHM_STREAM, 1u << 7)    /* STREAM_SHM available to Unix-socket clients */

/* A bit of the client's HELLO `features` only (never in a hello_reply): the client decodes the
 * owners trailer of a session_list (PROTOCOL.md 4.10, cluster mode); without it none is sent. */
#define DF_HELLO_WANT_OWNERS (1u << 16)

/* --------------------------------------------------------------------------------- enums */
#define DF_WIRE_LOAD_SOURCES(X) X(INLINE, 0) X(PATH, 1) /* DF_LOAD_*: bytes inline / a path */

#define DF_WIRE_LOAD_OPTS(X)                                                                 \
    X(EXT, 0x0001u) /* a str file_name follows the data; the reply is a load_reply */        \
    X(2D, 0x0002u)  /* a 2D session even if the file gives z (every z 0, no tetrahedra) */    \
    X(PROGRESS, 0x0004u) /* WORK_PROGRESS events of the upload and the parse (4.37) */

/* load_mesh `format` (DF_WFMT_*; core's df_mesh_format via proto/wire_core_map.h). TETGEN inline
 * data is the node bytes then the ele bytes. */
#define DF_WIRE_FORMATS(X) X(AUTO, 0) X(OBJ, 1) X(OFF, 2) X(PLY, 3) X(MEDIT, 4) X(TETGEN, 5)

#define DF_WIRE_MESH_KINDS(X) X(POLYLINE, 1) X(TRIANGLE, 2) X(TET, 3) /* DF_WKIND_* */

#define DF_WIRE_BRUSH_TYPES(X)                                                               \
    X(GRAB, 1)   /* uses move[] (tip displacement) */                                        \
    X(TWIST, 2)  /* uses twist[] (rotation vector: centre vorticity) */                      \
    X(SCALE, 3)  /* uses scale (centre dilation) */                                          \
    X(PINCH, 4)  /* uses matrix[] (symmetric, traceless centre gradient) */                  \
    X(AFFINE, 5) /* uses matrix[] (general centre gradient) */

#define DF_WIRE_INTEGRATORS(X) X(EULER, 1) X(RK4, 2) /* DF_INTEG_*: forward Euler / RK4 */

#define DF_WIRE_BRUSH_PARAMS(X)                                                              \
    X(RADIUS, 1)   /* value > 0, finite, mesh units */                                       \
    X(NU, 2)       /* Poisson ratio, not NaN; +-inf allowed */                               \
    X(STRENGTH, 3) /* multiplier on the load, finite */                                      \
    X(FALLOFF, 4)  /* integer 1..DF_MAX_FALLOFF */                                           \
    X(RATIO, 5)    /* multi-scale radius ratio, finite, > 1 */

#define DF_WIRE_ENERGIES(X) X(ARAP, 1) X(ACAP, 2) X(NEOHOOKEAN, 3) X(CLOTH, 4) X(POLYLINE, 5)

#define DF_WIRE_CHANGE_KINDS(X)                                                              \
    X(BRUSH, 1)        /* a brush begin/update of a stroke */                                \
    X(BRUSH_CANCEL, 2) /* a stroke cancelled: back to its start */                           \
    X(HANDLE_MOVE, 3)  /* an ADMM iterate (progress events) */                               \
    X(UNDO, 4) X(REDO, 5)                                                                    \
    X(RESET_REST, 6)   /* rest shape := current positions; positions unchanged */            \
    X(SNAPSHOT, 7)     /* full resync (snapshot reply / subscribe snapshot) */

#define DF_WIRE_DISP_ENCODINGS(X) X(DENSE, 1) X(SPARSE, 2) /* rows f32 xyz / (u32 index, xyz) */

#define DF_WIRE_MOVE_STATUSES(X)                                                             \
    X(RUNNING, 0)    /* more iterates follow */                                              \
    X(CONVERGED, 1)  /* residual <= tol */                                                   \
    X(BUDGET, 2)     /* stopped by max_iters or max_ms */                                    \
    X(SUPERSEDED, 3) /* a newer move on the same session replaced it */                      \
    X(FAILED, 4)     /* solver error (see stats / log) */

#define DF_WIRE_MESH_SECTIONS(X)                                                             \
    X(POSITIONS, 1) /* current positions, nv rows of f32 x,y,z */                            \
    X(BASE, 2)      /* base (load-time) positions: the stream's reference, nv rows */        \
    X(REST, 3)      /* current rest shape, nv rows of f32 x,y,z */                           \
    X(ELEMENTS, 4)  /* ne rows of elem_size u32 indices */                                   \
    X(FACES, 5)     /* nf rows of 3 u32 indices (tet boundary), may be absent */

#define DF_WIRE_PIN_FLAGS(X) X(DISPLACEMENT, 1u << 0) X(GRADIENT, 1u << 1) /* u = 0, grad u = 0 */
#define DF_WIRE_GET_MESH_FLAGS(X) X(REST, 1u << 0) X(BASE, 1u << 1) /* extra sections */
#define DF_WIRE_SUBSCRIBE_FLAGS(X)                                                           \
    X(SNAPSHOT, 1u << 0)     /* a dense snapshot right after */                               \
    X(FROM_VERSION, 1u << 1) /* resync: a u64 from_version follows; the versions after it */

/* Session brush state fields (DF_BS_*): brush_state_set `mask`, brush_state `changed`,
 * brush `use_session` (take these fields from the session brush instead of the message). */
#define DF_WIRE_BRUSH_STATE_FIELDS(X)                                                        \
    X(TYPE, 1u << 0) X(RADIUS, 1u << 1) X(NU, 1u << 2) X(STRENGTH, 1u << 3)                  \
    X(FALLOFF, 1u << 4) X(RATIO, 1u << 5)                                                    \
    X(INTEGRATOR, 1u << 6) /* integrator and steps */                                        \
    X(MIRROR, 1u << 7)     /* has_mirror, mirror_point, mirror_normal */

/* Who changed the session brush / moved a cursor (DF_ORIGIN_*; brush_state, brush_cursor). */
#define DF_WIRE_ORIGINS(X)                                                                   \
    X(NONE, 0)   /* nobody yet (the defaults) */                                             \
    X(CLIENT, 1) /* a client connection: id = connection id, name = its HELLO name */       \
    X(DEVICE, 2) /* an input device: id = device id, name = device name */

#define DF_WIRE_CURSOR_FLAGS(X) X(IN_RANGE, 1u << 0) X(STROKE_ACTIVE, 1u << 1) /* DF_CURSOR_* */

/* work_progress `stage` (DF_STAGE_*; PROTOCOL.md 4.37): what a long request is doing. New stages
 * are added at the end; clients show a stage they do not know by its number. */
#define DF_WIRE_WORK_STAGES(X)                                                               \
    X(UPLOAD, 1)    /* load: bytes of the inline upload received */                          \
    X(PARSE, 2)     /* load: bytes of the mesh file parsed */                                \
    X(FACTORIZE, 3) /* handles set / move: ADMM solver build (analysis, factorization) */     \
    X(SOLVE, 4)     /* handles move: ADMM iterations of the budget */

/* handles `options`, handle_move `options` (optional trailing u32, DF_WORK_OPT_*); brush_begin
 * `options`. KELVINLET_GUESS and POLISH are valid in handle_move only (elsewhere EPROTO_RESERVED). */
#define DF_WIRE_WORK_OPTS(X)                                                                 \
    X(PROGRESS, 1u << 0)        /* WORK_PROGRESS events of this request */                   \
    X(KELVINLET_GUESS, 1u << 1) /* handle_move: seed ADMM with the Kelvinlet guess */        \
    X(POLISH, 1u << 2)          /* handle_move: projected Newton after ADMM (df_admm_polish) */

/* devices (HID, issue 11): device_info `class`, `backend`, `state` (PROTOCOL.md 4.30) */
#define DF_WIRE_DEV_CLASSES(X)                                                               \
    X(NONE, 0)    /* not classified (not driven) */                                          \
    X(KNOB, 1)    /* dial / wheel with a button: radius, nu, falloff */                      \
    X(MOUSE3D, 2) /* multi-axis controller: cursor, grab strokes, twist */                   \
    X(PEN, 3)     /* digitizer pen: strokes through a bound view */
#define DF_WIRE_DEV_BACKENDS(X) X(HIDAPI, 1) X(LIBUSB, 2) X(REPLAY, 3) /* DF_DEVBACKEND_* */
#define DF_WIRE_DEV_STATES(X)                                                                \
    X(OPEN, 1)      /* open, reports are read */                                             \
    X(CLOSED, 2)    /* closed by the daemon (shutdown, disabled) */                          \
    X(ERROR, 3)     /* a read or write failed: closed, `error` says why */                   \
    X(UNPLUGGED, 4) /* gone (or the end of a replay): closed */

/* auth `method` (DF_AUTH_*; PROTOCOL.md 4.3): the two steps of the HMAC-SHA256 exchange */
#define DF_WIRE_AUTH_METHODS(X)                                                              \
    X(HMAC_CHALLENGE, 1) /* token: client nonce; reply token: server nonce */                \
    X(HMAC_PROOF, 2)     /* token: client MAC; reply token: server MAC */

/* access_info `mode` (DF_ACCESS_MODE_*; PROTOCOL.md 4.34, 4.36) */
#define DF_WIRE_ACCESS_MODES(X)                                                              \
    X(OPEN, 1)  /* every principal is a member: observe and edit */                          \
    X(KEY, 2)   /* members (JOIN with the join key) edit */                                  \
    X(OWNER, 3) /* only the owner and admins edit; members observe */
/* session_access `flags` (DF_ACCESS_*) */
#define DF_WIRE_ACCESS_FLAGS(X) X(NEW_KEY, 1u << 0) /* rotate the join key; the reply has it */

/* session peers (PROTOCOL.md 4.38): peer_info `flags` (DF_PEER_*) and `transport`
 * (DF_TRANSPORT_*) */
#define DF_WIRE_PEER_FLAGS(X)                                                                \
    X(SELF, 1u << 0) /* the connection that asked */                                         \
    X(EDIT, 1u << 1) /* its principal holds the edit right on the session */                 \
    X(SHM, 1u << 2)  /* it streams through the shared-memory ring (STREAM_SHM) */
#define DF_WIRE_TRANSPORTS(X) X(UNIX, 1) X(TCP, 2) /* the socket it is connected through */
/* the range of a quantized stream's error_bound (f64, mesh units) */
#define DF_STREAM_ERROR_LO 1e-30
#define DF_STREAM_ERROR_HI 1e30
/* hello / hello_reply `stream_encoding` (DF_STREAM_ENC_*; PROTOCOL.md 4.2, 4.40, 4.41): how the
 * connection's displacement stream travels. 0 (no bit) is exact float32, the default. */
#define DF_WIRE_STREAM_ENCS(X)                                                               \
    X(QUANTIZED, 1u << 0) /* QDISP events: deltas quantized to 2 x error_bound */           \
    X(ZSTD, 1u << 1)      /* stream events may come as ZFRAME (zstd) */

/* Every enum list: X(list macro, C prefix, Python class, kind) for tools that walk them all. */
#define DF_WIRE_ENUMS(X)                                                                     \
    X(DF_WIRE_FLAGS, DF_FLAG_, FrameFlag, flags)                                                \
    X(DF_WIRE_FEATURES, DF_FEAT_, Feature, flags)                                            \
    X(DF_WIRE_LOAD_SOURCES, DF_LOAD_, LoadSource, enum)                                      \
    X(DF_WIRE_LOAD_OPTS, DF_LOAD_OPT_, LoadOpt, flags)                                       \
    X(DF_WIRE_FORMATS, DF_WFMT_, Format, enum)                                               \
    X(DF_WIRE_MESH_KINDS, DF_WKIND_, MeshKind, enum)                                         \
    X(DF_WIRE_BRUSH_TYPES, DF_BRUSH_, BrushType, enum)                                       \
    X(DF_WIRE_INTEGRATORS, DF_INTEG_, Integrator, enum)                                      \
    X(DF_WIRE_BRUSH_PARAMS, DF_BP_, BrushParam, enum)                                        \
    X(DF_WIRE_ENERGIES, DF_ENERGY_, Energy, enum)                                            \
    X(DF_WIRE_CHANGE_KINDS, DF_CHANGE_, ChangeKind, enum)                                    \
    X(DF_WIRE_DISP_ENCODINGS, DF_DISP_, DispEncoding, enum)                                  \
    X(DF_WIRE_MOVE_STATUSES, DF_MOVE_, MoveStatus, enum)                                     \
    X(DF_WIRE_MESH_SECTIONS, DF_SECTION_, MeshSection, enum)                                 \
    X(DF_WIRE_PIN_FLAGS, DF_PIN_, PinFlag, flags)                                            \
    X(DF_WIRE_GET_MESH_FLAGS, DF_GET_MESH_, GetMeshFlag, flags)                              \
    X(DF_WIRE_SUBSCRIBE_FLAGS, DF_SUBSCRIBE_, SubscribeFlag, flags)                          \
    X(DF_WIRE_BRUSH_STATE_FIELDS, DF_BS_, BrushStateField, flags)                            \
    X(DF_WIRE_ORIGINS, DF_ORIGIN_, Origin, enum)                                             \
    X(DF_WIRE_CURSOR_FLAGS, DF_CURSOR_, CursorFlag, flags)                                   \
    X(DF_WIRE_DEV_CLASSES, DF_DEVCLASS_, DevClass, enum)                                     \
    X(DF_WIRE_DEV_BACKENDS, DF_DEVBACKEND_, DevBackend, enum)                                \
    X(DF_WIRE_DEV_STATES, DF_DEVSTATE_, DevState, enum)                                      \
    X(DF_WIRE_AUTH_METHODS, DF_AUTH_, AuthMethod, enum)                                      \
    X(DF_WIRE_ACCESS_MODES, DF_ACCESS_MODE_, AccessMode, enum)                               \
    X(DF_WIRE_ACCESS_FLAGS, DF_ACCESS_, AccessFlag, flags)                               \
    X(DF_WIRE_WORK_STAGES, DF_STAGE_, WorkStage, enum)                                       \
    X(DF_WIRE_WORK_OPTS, DF_WORK_OPT_, WorkOpt, flags)                                       \
    X(DF_WIRE_PEER_FLAGS, DF_PEER_, PeerFlag, flags)                                         \
    X(DF_WIRE_TRANSPORTS, DF_TRANSPORT_, Transport, enum)                                    \
    X(DF_WIRE_STREAM_ENCS, DF_STREAM_ENC_, StreamEnc, flags)

/* ------------------------------------------------------------------------------- defaults
 * The brush every client starts from (df_msg_brush_defaults, Python Brush()): GRAB, 3D, falloff
 * 1, Euler 1 step, stationary, no mirror (normal (1,0,0)), zero loads, no pins. The handle-set
 * (ADMM) defaults are the solver's own, in core/admm/admm_defaults.h. */
#define DF_WIRE_BRUSH_DEFAULTS(X)                                                            \
    X(type, DF_BRUSH_GRAB) X(dim, 3) X(falloff, 1) X(integrator, DF_INTEG_EULER) X(steps, 1)  \
    X(radius, 1.0) X(ratio, 1.1) X(nu, 0.5) X(strength, 1.0)

#endif
