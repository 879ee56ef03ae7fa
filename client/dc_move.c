/* dc_move.c — libdeformclient's cluster redirect: EMOVED reconnects to the session's owner
 * (see dc_client.h dc_move, deformclient.h df_client_set_follow_moved). */
#include "client/dc_client.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "client/dc_net.h"
#include "client/dc_tls.h"

void df_client_set_follow_moved(df_client *c, int on)
{
    if (c) c->follow_moved = on != 0;
}

int df_client_moves(const df_client *c)
{
    return c ? c->moves : 0;
}

/* "MOVED <id> <host:port>" -> host (cap bytes), *port. 0 when not of that form. */
static int parse_moved(const char *msg, char *host, size_t cap, int *port)
{
    unsigned long long id;
    char addr[300];
    if (sscanf(msg, "MOVED %llu %299s", &id, addr) != 2) return 0;
    char *colon = strrchr(addr, ':');
    char *end = NULL;
    long p = colon ? strtol(colon + 1, &end, 10) : 0;
    if (!colon || colon == addr || !end || *end || p < 1 || p > 65535) return 0;
    *colon = '\0';
    char *h = addr;
    if (h[0] == '[' && colon[-1] == ']') { /* [v6]:port */
        h++;
        colon[-1] = '\0';
    }
    size_t n = strlen(h);
    if (n >= cap) return 0;
    memcpy(host, h, n + 1);
    *port = (int)p;
    return 1;
}

int dc_move(df_client *c, const char *moved_msg, df_error *err)
{
    char host[256];
    int port;
    if (!parse_moved(moved_msg, host, sizeof host, &port))
        return df_error_set(err, DF_EINVAL, "not a MOVED redirect: %s", moved_msg);
    int fd = dc_net_connect_tcp(host, port, err);
    if (fd < 0) return fd;
    dc_tls_end(c);
    if (c->fd >= 0) close(c->fd);
    dc_shm_drop(c, 0);
    c->fd = fd;
    c->rpos = c->rlen = 0;
    c->broken = 0;
    char name[sizeof c->name];
    memcpy(name, c->name, sizeof name);
    int rc = c->tls_ca ? dc_tls_start(c, host, c->tls_ca, err) : DF_OK;
    if (rc == DF_OK) rc = dc_hello(c, name, err);
    if (rc == DF_OK && c->key) rc = df_client_authenticate(c, c->key, c->key_len, err);
    if (rc != DF_OK) {
        c->broken = 1;
        return rc;
    }
    c->moves++;
    return DF_OK;
}
