/* h_mesh.c — undo / redo, get-mesh (chunked) and snapshot (see handlers.h).
 *
 * Undo / redo restore the previous / next committed state (stroke end, handle move) and publish
 * it as a NEW version (kind UNDO / REDO), so the stream stays append-only. */
#include <stdlib.h>
#include <string.h>

#include "server/net/conn.h"
#include "server/handlers/handlers.h"
#include "server/exec/job.h"
#include "server/net/reply.h"
#include "server/session/stream.h"

typedef struct mesh_req {
    uint64_t version;          /* snapshot: requested version (0 = current) */
    uint32_t flags;            /* get-mesh flags */
    df_frames frames;
} mesh_req;

static void req_free(df_server *srv, void *body)
{
    (void)srv;
    df_frames_clear(&((mesh_req *)body)->frames);
}

/* Sends the job's frames to the requester only: a multi-frame reply (the last is final). */
static void reply_frames(df_job *j)
{
    mesh_req *r = j->body;
    for (size_t i = 0; i + 1 < r->frames.n; i++) df_req_reply_more(&j->req, r->frames.v[i]);
    if (r->frames.n) df_req_reply(&j->req, r->frames.v[r->frames.n - 1]);
}

/* ---- undo / redo ---- */

/* Work of UNDO / REDO (pure: fills j->change). */
static void history_work(df_job *j)
{
    const df_session *s = j->s;
    int undo = j->req.type == DF_MSG_UNDO;
    if (s->strokes) {
        j->rc = df_error_set(&j->err, DF_ESTATE, "%s: a brush stroke is open on session %llu",
                             undo ? "undo" : "redo", (unsigned long long)s->id);
        return;
    }
    if (undo ? !df_history_can_undo(&s->hist) : !df_history_can_redo(&s->hist)) {
        j->rc = df_error_set(&j->err, DF_ESTATE, "%s: nothing to %s on session %llu",
                             undo ? "undo" : "redo", undo ? "undo" : "redo",
                             (unsigned long long)s->id);
        return;
    }
    /* The target state is rebuilt from the history (replaying recipe steps, history.h) into
     * the scratch positions the job borrowed; the commit swaps them in and installs the plan
     * (commit.h). A replay mismatch fails the request and the commit repairs the history. */
    double *state = s->scratch_pos;
    df_change *ch = &j->change;
    j->rc = df_history_plan_move(&s->hist, undo ? -1 : 1, state, &ch->hplan, &j->err);
    if (j->rc != DF_OK) return;
    j->rc = df_stream_encode(s, NULL, 0, state, undo ? DF_CHANGE_UNDO : DF_CHANGE_REDO, NULL,
                             0, s->scratch_u, &ch->frames, NULL, &j->err);
    if (j->rc != DF_OK) return;
    ch->pos = state;
    ch->uf = s->scratch_u;
    ch->version = atomic_load(&s->version) + 1;
    ch->hist = undo ? DF_HIST_UNDO : DF_HIST_REDO;
}

const df_job_kind df_k_history = {.body_size = sizeof(mesh_req), .decode = df_job_decode_ref,
                                  .release = req_free, .work = history_work,
                                  .done = df_job_commit,
                                  .beside = DF_JOB_BESIDE_REFUSE}; /* ESTATE beside a move */

/* ---- get mesh ---- */

/* Appends the chunks of one section (rows of `width` values: floats or int32). */
static int add_section(df_job *j, uint8_t section, uint32_t rows, int width, const float *xyz,
                       const int32_t *idx, int last_section)
{
    mesh_req *r = j->body;
    df_session *s = j->s;
    size_t row_bytes = (size_t)width * 4;
    uint32_t per = (uint32_t)(DF_STREAM_CHUNK_BYTES / row_bytes);
    uint32_t off = 0;
    do {
        uint32_t cnt = rows - off < per ? rows - off : per;
        df_msg_mesh_chunk m;
        memset(&m, 0, sizeof m);
        m.session_id = s->id;
        m.version = atomic_load(&s->version);
        m.kind = (uint8_t)s->mesh.kind;
        m.planar = (uint8_t)(s->mesh.planar != 0);
        m.section = section;
        m.nv = (uint32_t)s->nv;
        m.ne = (uint32_t)s->mesh.ne;
        m.nf = (uint32_t)s->mesh.nf;
        m.offset = off;
        m.count = cnt;
        if (xyz) m.xyz = (float *)(xyz + (size_t)off * 3);
        if (idx) m.idx = (int32_t *)(idx + (size_t)off * width);
        int last = last_section && off + cnt >= rows;
        df_sbuf *f = df_out_mesh_chunk(j->req.type,
                                       (uint16_t)(DF_FLAG_REPLY | (last ? 0 : DF_FLAG_MORE)),
                                       j->req.id, &m, &j->err);
        if (!f) return j->err.code;
        if (df_frames_push(&r->frames, f) != DF_OK)
            return df_error_set(&j->err, DF_ENOMEM, "out of memory");
        off += cnt;
    } while (off < rows);
    return DF_OK;
}

static void get_mesh_work(df_job *j)
{
    mesh_req *r = j->body;
    df_session *s = j->s;
    size_t n = 3 * (size_t)s->nv;
    float *buf = malloc(n * sizeof *buf);
    if (!buf) {
        j->rc = df_error_set(&j->err, DF_ENOMEM, "out of memory");
        return;
    }
    int es = df_mesh_elem_size(s->mesh.kind);
    int has_faces = s->mesh.nf > 0;
    df_stream_positions(s, buf);
    int rc = add_section(j, DF_SECTION_POSITIONS, (uint32_t)s->nv, 3, buf, NULL, 0);
    if (rc == DF_OK && (r->flags & DF_GET_MESH_BASE))
        rc = add_section(j, DF_SECTION_BASE, (uint32_t)s->nv, 3, s->basef, NULL, 0);
    if (rc == DF_OK && (r->flags & DF_GET_MESH_REST)) {
        /* same representation as positions: fl32(fl32(X) + fl32(rest - X)) */
        for (size_t i = 0; i < n; i++) buf[i] = s->basef[i] + (float)(s->rest[i] - s->mesh.V[i]);
        rc = add_section(j, DF_SECTION_REST, (uint32_t)s->nv, 3, buf, NULL, 0);
    }
    if (rc == DF_OK)
        rc = add_section(j, DF_SECTION_ELEMENTS, (uint32_t)s->mesh.ne, es, NULL, s->mesh.E,
                         !has_faces);
    if (rc == DF_OK && has_faces)
        rc = add_section(j, DF_SECTION_FACES, (uint32_t)s->mesh.nf, 3, NULL, s->mesh.F, 1);
    free(buf);
    j->rc = rc;
}

static void frames_done(df_job *j)
{
    if (df_job_failed(j)) return;
    reply_frames(j);
}

/* Decodes a get-mesh or a snapshot request into its mesh_req. */
static int read_decode(const df_req *rq, const uint8_t *p, void *body, uint64_t *sid,
                       df_error *err)
{
    mesh_req *r = body;
    df_msg_get_mesh g;
    df_msg_snapshot_req q;
    int rc = rq->type == DF_MSG_GET_MESH ? df_msg_get_mesh_decode(p, rq->len, &g, err)
                                         : df_msg_snapshot_req_decode(p, rq->len, &q, err);
    if (rc != DF_OK) return rc;
    *sid = rq->type == DF_MSG_GET_MESH ? g.session_id : q.session_id;
    if (rq->type == DF_MSG_GET_MESH) r->flags = g.flags;
    else r->version = q.version;
    return DF_OK;
}

/* get-mesh and snapshot answer the last published version while a move runs */
const df_job_kind df_k_get_mesh = {.body_size = sizeof(mesh_req), .decode = read_decode,
                                   .release = req_free, .work = get_mesh_work,
                                   .done = frames_done, .beside = DF_JOB_BESIDE_READ};

/* ---- snapshot ---- */

static void snapshot_work(df_job *j)
{
    mesh_req *r = j->body;
    df_session *s = j->s;
    uint64_t v = atomic_load(&s->version);
    if (r->version != 0 && r->version != v) {
        j->rc = df_error_set(&j->err, DF_ENOTFOUND,
                             "snapshot: version %llu is not retained (current %llu; ask for 0)",
                             (unsigned long long)r->version, (unsigned long long)v);
        return;
    }
    j->rc = df_stream_snapshot(s, DF_MSG_SNAPSHOT, j->req.id, &r->frames, &j->err);
}

const df_job_kind df_k_snapshot = {.body_size = sizeof(mesh_req), .decode = read_decode,
                                   .release = req_free, .work = snapshot_work,
                                   .done = frames_done, .beside = DF_JOB_BESIDE_READ};
