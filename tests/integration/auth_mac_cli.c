/* auth_mac_cli.c — prints the AUTH MAC of proto/auth_mac.c for test_auth.py (the worked example
 * of PROTOCOL.md 4.3 checked against the C implementation):
 *   auth_mac_cli KEY_TEXT NS_HEX NC_HEX client|server   -> 64 hex digits and a newline
 * KEY_TEXT is used as bytes (like a key file's contents). Exit 2 on bad arguments, 1 on error. */
#include <stdio.h>
#include <string.h>

#include "proto/auth_mac.h"

static int unhex(const char *s, uint8_t *out, size_t n)
{
    if (strlen(s) != 2 * n) return -1;
    for (size_t i = 0; i < n; i++) {
        unsigned v;
        if (sscanf(s + 2 * i, "%2x", &v) != 1) return -1;
        out[i] = (uint8_t)v;
    }
    return 0;
}

int main(int argc, char **argv)
{
    uint8_t ns[DF_AUTH_NONCE_BYTES], nc[DF_AUTH_NONCE_BYTES], mac[DF_AUTH_MAC_BYTES];
    if (argc != 5 || unhex(argv[2], ns, sizeof ns) || unhex(argv[3], nc, sizeof nc) ||
        (strcmp(argv[4], "client") && strcmp(argv[4], "server"))) {
        fprintf(stderr, "usage: auth_mac_cli KEY_TEXT NS_HEX NC_HEX client|server\n");
        return 2;
    }
    df_error e;
    if (df_auth_mac((const uint8_t *)argv[1], strlen(argv[1]), ns, nc,
                    strcmp(argv[4], "client") == 0 ? DF_AUTH_ROLE_CLIENT : DF_AUTH_ROLE_SERVER,
                    mac, &e) != DF_OK) {
        fprintf(stderr, "%s\n", e.msg);
        return 1;
    }
    for (size_t i = 0; i < sizeof mac; i++) printf("%02x", mac[i]);
    printf("\n");
    return 0;
}
