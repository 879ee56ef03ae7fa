/* access.c — per-session rights and per-principal quotas (see access.h). */
#include "server/session/access.h"

#include <string.h>

#include "proto/messages.h"

int df_access_needed(uint16_t type)
{
    switch (type) {
    case DF_MSG_SUBSCRIBE: case DF_MSG_UNSUBSCRIBE: case DF_MSG_STREAM_SHM:
    case DF_MSG_GET_MESH: case DF_MSG_SNAPSHOT: case DF_MSG_HANDLES_GET:
    case DF_MSG_BRUSH_STATE_GET: case DF_MSG_SESSION_PEERS:
        return DF_RIGHT_OBSERVE;
    case DF_MSG_BRUSH_BEGIN: case DF_MSG_BRUSH_UPDATE: case DF_MSG_BRUSH_END:
    case DF_MSG_BRUSH_CANCEL: case DF_MSG_SET_BRUSH_PARAM: case DF_MSG_BRUSH_STATE_SET:
    case DF_MSG_HANDLES_SET: case DF_MSG_HANDLES_MOVE: case DF_MSG_UNDO: case DF_MSG_REDO:
    case DF_MSG_DEVICE_BIND: case DF_MSG_DEVICE_VIEW:
        return DF_RIGHT_EDIT;
    case DF_MSG_CLOSE_SESSION: case DF_MSG_RESET_REST:
        return DF_RIGHT_OWN;
    default:
        return 0;
    }
}

int df_access_rights(const df_conn *c, const df_session *s)
{
    if (!c) return DF_RIGHT_OBSERVE | DF_RIGHT_EDIT | DF_RIGHT_OWN;
    return df_membership_rights(&s->acc, s->owner, c->principal, c->admin);
}

_Static_assert((int)DF_RIGHT_OBSERVE == (int)DF_MEMBER_OBSERVE &&
               (int)DF_RIGHT_EDIT == (int)DF_MEMBER_EDIT && (int)DF_RIGHT_OWN == (int)DF_MEMBER_OWN, "membership rights are access rights");

static const char *right_name(int right)
{
    return right == DF_RIGHT_OWN ? "own" : right == DF_RIGHT_EDIT ? "edit" : "observe";
}

/* How a principal without `need` gets it on `s`. */
static const char *how_to_get(int need, const df_session *s)
{
    if (need == DF_RIGHT_OWN) return "only the owner or an admin key has it";
    if (s->acc.mode == DF_ACCESS_MODE_KEY)
        return "join with the session's key: JOIN, deformctl join SESSION --key HEX";
    if (need == DF_RIGHT_EDIT)
        return "the session is owner-only: its owner may switch it to key mode";
    return "the session admits no observers: its owner may give you its join key";
}

int df_access_check(const df_req *r, const df_session *s, df_error *err)
{
    return df_access_require(r, s, df_access_needed(r->type), err);
}

int df_access_require(const df_req *r, const df_session *s, int need, df_error *err)
{
    int have = df_access_rights(r->c, s);
    if ((have & need) == need || !r->c) return DF_OK;
    const char *role = (have & DF_RIGHT_EDIT)      ? "a member"
                       : (have & DF_RIGHT_OBSERVE) ? "an observer"
                                                   : "not admitted";
    return df_error_set(err, DF_EPERM,
                        "%s: session '%s' needs the %s right (you are %s, %s; owner %s; "
                        "%s mode): %s", df_msg_type_name(r->type), s->name, right_name(need),
                        r->c->principal, role, s->owner[0] ? s->owner : "none (admins)",
                        df_membership_mode_name(s->acc.mode), how_to_get(need, s));
}

int df_access_quota_check(df_server *srv, const char *who, uint64_t upload_bytes,
                          uint64_t mem_bytes, df_error *err)
{
    const df_access_config *a = &srv->cfg.access;
    int n = 0;
    uint64_t up = 0, mem = 0;
    for (const df_session *s = srv->sessions; s; s = s->next) {
        if (s->closed || strcmp(s->owner, who) != 0) continue;
        n++;
        up += s->upload_bytes;
        mem += s->mem_bytes + s->hist_charged + s->shm_charged; /* stats memory_bytes */
    }
    const double mib = 1024.0 * 1024.0;
    if (a->quota_sessions && n + 1 > a->quota_sessions)
        return df_error_set(err, DF_ELIMIT,
                            "quota_sessions: %s owns %d live sessions, the limit is %d (close "
                            "one first)", who, n, a->quota_sessions);
    if (a->quota_upload_mb && up + upload_bytes > ((uint64_t)a->quota_upload_mb << 20))
        return df_error_set(err, DF_ELIMIT,
                            "quota_upload_mb: %s's sessions hold %.2f MiB of uploads, %.2f MiB "
                            "more would exceed the limit of %d MiB", who, (double)up / mib,
                            (double)upload_bytes / mib, a->quota_upload_mb);
    if (a->quota_memory_mb && mem + mem_bytes > ((uint64_t)a->quota_memory_mb << 20))
        return df_error_set(err, DF_ELIMIT,
                            "quota_memory_mb: %s's sessions hold %.2f MiB of memory, %.2f MiB "
                            "more would exceed the limit of %d MiB", who, (double)mem / mib,
                            (double)mem_bytes / mib, a->quota_memory_mb);
    return DF_OK;
}
