/* msg_types.c — message type names and the (type, flags) -> body table (messages.h). */
#include "proto/messages.h"

typedef struct type_row {
    uint16_t type;
    const char *name;
    df_body_kind request;  /* body sent by the client, DF_BODY_ERROR if not a request */
    df_body_kind reply;    /* body of the reply, DF_BODY_ERROR if none */
    df_body_kind event;    /* body as an event, DF_BODY_ERROR if never an event */
} type_row;

#define NONE DF_BODY_ERROR

static const type_row rows[] = {
    {DF_MSG_HELLO, "hello", DF_BODY_HELLO, DF_BODY_HELLO_REPLY, NONE},
    {DF_MSG_AUTH, "auth", DF_BODY_AUTH, DF_BODY_EMPTY, NONE},
    {DF_MSG_PING, "ping", DF_BODY_PING, DF_BODY_PING, NONE},
    {DF_MSG_LOAD_MESH, "load_mesh", DF_BODY_LOAD_MESH, DF_BODY_LOAD_REPLY, NONE},
    {DF_MSG_LIST_SESSIONS, "list_sessions", DF_BODY_EMPTY, DF_BODY_SESSION_LIST, NONE},
    {DF_MSG_OPEN_SESSION, "open_session", DF_BODY_OPEN_SESSION, DF_BODY_SESSION_INFO, NONE},
    {DF_MSG_CLOSE_SESSION, "close_session", DF_BODY_SESSION_REF, DF_BODY_ACK, NONE},
    {DF_MSG_SUBSCRIBE, "subscribe", DF_BODY_SUBSCRIBE, DF_BODY_SESSION_INFO, NONE},
    {DF_MSG_UNSUBSCRIBE, "unsubscribe", DF_BODY_SESSION_REF, DF_BODY_ACK, NONE},
    {DF_MSG_STREAM_SHM, "stream_shm", DF_BODY_SESSION_REF, DF_BODY_SHM_INFO, NONE},
    {DF_MSG_BRUSH_BEGIN, "brush_begin", DF_BODY_BRUSH, DF_BODY_ACK, NONE},
    {DF_MSG_BRUSH_UPDATE, "brush_update", DF_BODY_BRUSH_UPDATE, DF_BODY_ACK, NONE},
    {DF_MSG_BRUSH_END, "brush_end", DF_BODY_SESSION_REF, DF_BODY_ACK, NONE},
    {DF_MSG_BRUSH_CANCEL, "brush_cancel", DF_BODY_SESSION_REF, DF_BODY_ACK, NONE},
    {DF_MSG_SET_BRUSH_PARAM, "set_brush_param", DF_BODY_BRUSH_PARAM, DF_BODY_ACK, NONE},
    {DF_MSG_HANDLES_SET, "handles_set", DF_BODY_HANDLES, DF_BODY_ACK, NONE},
    {DF_MSG_HANDLES_MOVE, "handles_move", DF_BODY_HANDLE_MOVE, DF_BODY_MOVE_RESULT, NONE},
    {DF_MSG_RESET_REST, "reset_rest", DF_BODY_SESSION_REF, DF_BODY_ACK, NONE},
    {DF_MSG_UNDO, "undo", DF_BODY_SESSION_REF, DF_BODY_ACK, NONE},
    {DF_MSG_REDO, "redo", DF_BODY_SESSION_REF, DF_BODY_ACK, NONE},
    {DF_MSG_HANDLES_GET, "handles_get", DF_BODY_SESSION_REF, DF_BODY_HANDLES, NONE},
    {DF_MSG_GET_MESH, "get_mesh", DF_BODY_GET_MESH, DF_BODY_MESH_CHUNK, NONE},
    {DF_MSG_SNAPSHOT, "snapshot", DF_BODY_SNAPSHOT_REQ, DF_BODY_DISP, NONE},
    {DF_MSG_STATS, "stats", DF_BODY_STATS_REQ, DF_BODY_STATS, NONE},
    {DF_MSG_DISPLACEMENT, "displacement", NONE, NONE, DF_BODY_DISP},
    {DF_MSG_PROGRESS, "progress", NONE, NONE, DF_BODY_PROGRESS},
    {DF_MSG_SESSION_CLOSED, "session_closed", NONE, NONE, DF_BODY_SESSION_REF},
    {DF_MSG_SHM_REF, "shm_ref", NONE, NONE, DF_BODY_SHM_REF},
    {DF_MSG_ERROR, "error", NONE, NONE, NONE},
};

static const type_row *find(uint16_t type)
{
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++)
        if (rows[i].type == type)
            return &rows[i];
    return NULL;
}

int df_msg_type_valid(uint16_t type)
{
    return find(type) != NULL;
}

const char *df_msg_type_name(uint16_t type)
{
    const type_row *r = find(type);
    return r ? r->name : "unknown";
}

int df_msg_body_kind(uint16_t type, uint16_t flags, df_body_kind *out, df_error *err)
{
    const type_row *r = find(type);
    if (!r)
        return df_error_set(err, DF_EPROTO_BADTYPE, "unknown message type 0x%04x", type);
    if (flags & DF_FLAG_ERROR) {
        *out = DF_BODY_ERROR;
        return DF_OK;
    }
    df_body_kind k = (flags & DF_FLAG_REPLY) ? r->reply
                     : (flags & DF_FLAG_EVENT) ? r->event : r->request;
    if (k == NONE)
        return df_error_set(err, DF_EPROTO_BADTYPE, "message type %s (0x%04x) is not valid as %s",
                            r->name, type, (flags & DF_FLAG_REPLY)   ? "a reply"
                                           : (flags & DF_FLAG_EVENT) ? "an event"
                                                                     : "a request");
    *out = k;
    return DF_OK;
}
