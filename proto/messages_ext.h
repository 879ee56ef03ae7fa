/* messages_ext.h — the body structs of the later message types: HID devices (PROTOCOL.md
 * 4.30-4.33), per-session access (4.34-4.36), session peers (4.38) and the negotiated stream
 * encodings (4.40, 4.41). Part of proto/messages.h, which includes it after the enums and the
 * earlier bodies and declares every codec (df_msg_*_encode / _decode / _free); include
 * proto/messages.h, not this file. */
#ifndef DF_PROTO_MESSAGES_EXT_H
#define DF_PROTO_MESSAGES_EXT_H

#ifndef DF_PROTO_MESSAGES_H
#error "include proto/messages.h (it includes proto/messages_ext.h)"
#endif

/* ---------------------------------------------------------------- devices (HID, issue 11) */
typedef struct df_msg_device_info {    /* one device (DEVICES_LIST item, DEVICE_STATE event) */
    uint64_t device_id;                /* != 0 (the daemon uses (1 << 63) | n) */
    uint8_t dev_class;                 /* DF_DEVCLASS_* 0..3 */
    uint8_t backend;                   /* DF_DEVBACKEND_* 1..3 */
    uint8_t state;                     /* DF_DEVSTATE_* 1..4 */
    uint8_t bus;                       /* linux/input.h bus: 3 USB, 5 BT, 0x18 I2C (any value) */
    uint16_t vid, pid;
    uint64_t bound_session;            /* 0: follows the most recently active session */
    uint64_t active_session;           /* the session it drives now, 0 none */
    uint8_t haptics;                   /* 0/1: haptic output enabled */
    char name[DF_MAX_NAME_LEN + 1];    /* product name, may be "" */
    char path[DF_MAX_PATH_LEN + 1];    /* backend path, may be "" */
    char error[DF_MAX_ERROR_MSG_LEN + 1]; /* why it is in state ERROR/UNPLUGGED, else "" */
} df_msg_device_info;

typedef struct df_msg_device_list {
    uint32_t count;                    /* 0..DF_MAX_DEVICES */
    df_msg_device_info *items;         /* malloc'd on decode */
} df_msg_device_list;

typedef struct df_msg_device_bind {
    uint64_t device_id;                /* != 0 */
    uint64_t session_id;               /* 0 = unbind: follow the most recently active session */
} df_msg_device_bind;

typedef struct df_msg_device_view {    /* the view a pen's 2D position is cast through */
    uint64_t device_id;                /* != 0 */
    uint64_t session_id;               /* != 0 */
    double view_proj[16];              /* row-major 4x4, mesh space -> clip (OpenGL), finite */
    double viewport[4];                /* x, y, width, height in pixels (y down), finite,
                                        * width and height > 0 */
} df_msg_device_view;

/* ------------------------------------------------------- per-session access (PROTOCOL.md 4.34) */
typedef struct df_msg_session_access { /* SESSION_ACCESS: all of mode, observers, flags 0 = get */
    uint64_t session_id;               /* != 0 */
    uint8_t mode;                      /* 0 keep, else DF_ACCESS_MODE_* */
    uint8_t observers;                 /* 0 keep, 1 off, 2 on */
    uint8_t flags;                     /* DF_ACCESS_* bits (NEW_KEY) */
} df_msg_session_access;

typedef struct df_msg_join {           /* JOIN: become a member with the session's join key */
    uint64_t session_id;               /* != 0 */
    uint8_t key[DF_JOIN_KEY_BYTES];
} df_msg_join;

typedef struct df_msg_access_info {    /* SESSION_ACCESS / JOIN reply: the session's policy */
    uint64_t session_id;               /* != 0 */
    uint8_t mode;                      /* DF_ACCESS_MODE_* */
    uint8_t observers;                 /* 0/1 */
    uint32_t members;                  /* principals that joined (key mode) */
    char owner[DF_MAX_NAME_LEN + 1];   /* the owner's principal ("" when none is recorded) */
    uint8_t has_key;                   /* 1: `key` is a new join key (NEW_KEY, owner only) */
    uint8_t key[DF_JOIN_KEY_BYTES];
} df_msg_access_info;

/* ------------------------------------------------------ session peers (PROTOCOL.md 4.38) */
typedef struct df_msg_peer_info {      /* one connection subscribed to a session */
    uint64_t client_id;                /* != 0: the daemon's connection id */
    uint8_t flags;                     /* DF_PEER_* bits (SELF, EDIT, SHM) */
    uint8_t transport;                 /* DF_TRANSPORT_* 1..DF_TRANSPORT_MAX */
    char name[DF_MAX_NAME_LEN + 1];    /* the client_name of its HELLO, may be "" */
    char principal[DF_MAX_NAME_LEN + 1]; /* who it acts as: "uid:1000", "key:NAME", ... */
} df_msg_peer_info;

typedef struct df_msg_peer_list {      /* SESSION_PEERS reply */
    uint32_t count;                    /* 0..DF_MAX_PEERS */
    df_msg_peer_info *items;           /* malloc'd on decode */
} df_msg_peer_list;

/* ------------------------------------------ negotiated stream encodings (PROTOCOL.md 4.40, 4.41) */
typedef struct df_msg_qdisp {          /* QDISP event: one chunk of a quantized version delta */
    uint64_t session_id;               /* != 0 */
    uint64_t version;                  /* version this frame produces */
    uint64_t base_version;             /* < version */
    uint8_t kind;                      /* df_change_kind 1..6 (never SNAPSHOT) */
    uint32_t nv;                       /* mesh vertex count, 1..DF_MAX_MESH_VERTICES */
    uint32_t count;                    /* rows in this chunk, <= nv */
    double step;                       /* quantization step q (2 x error bound), finite, > 0 */
    int32_t *idx;                      /* count vertex indices, strictly increasing, < nv */
    int64_t *dq;                       /* count x 3 changes of the quantized displacement, in
                                        * steps (|dq| < 2^53); malloc'd on decode */
    /* optional progress trailer (PROTOCOL.md 4.40): a PROGRESS iterate's fields, kind 3 only */
    uint8_t has_progress;              /* 1: the trailer is present */
    uint8_t status, final;             /* as progress: final iff status != running */
    uint32_t iteration;                /* 1-based */
    double objective, residual, elapsed_ms; /* finite; residual, elapsed_ms >= 0 */
} df_msg_qdisp;

typedef struct df_msg_zframe {         /* ZFRAME event: a stream event frame compressed by zstd */
    uint16_t inner_type;               /* DF_MSG_DISPLACEMENT, DF_MSG_PROGRESS or DF_MSG_QDISP */
    uint32_t raw_len;                  /* bytes of the inner payload, <= DF_MAX_FRAME_PAYLOAD */
    uint32_t zlen;                     /* bytes of `z`, >= 1 */
    const uint8_t *z;                  /* one zstd frame; points into the payload (decode) */
} df_msg_zframe;

#endif
