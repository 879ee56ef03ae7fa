/* msg_types.c — message type names and the (type, flags) -> body table (messages.h). */
#include "proto/messages.h"

typedef struct type_row {
    uint16_t type;
    const char *name;
    df_body_kind request;  /* body sent by the client, DF_BODY_ERROR if not a request */
    df_body_kind reply;    /* body of the reply, DF_BODY_ERROR if none */
    df_body_kind event;    /* body as an event, DF_BODY_ERROR if never an event */
} type_row;

/* Built from DF_WIRE_MSG_TYPES (proto/wire_schema.h); NONE: not valid in that direction. */
#define DF_BODY_NONE DF_BODY_ERROR
#define NONE DF_BODY_NONE
#define DF_X_ROW(n, v, name, req, rep, ev) \
    {DF_MSG_##n, #name, DF_BODY_##req, DF_BODY_##rep, DF_BODY_##ev},

static const type_row rows[] = {DF_WIRE_MSG_TYPES(DF_X_ROW)};
#undef DF_X_ROW

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
