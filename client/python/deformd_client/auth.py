"""TCP key authentication of deformd (PROTOCOL.md 4.3), standard library only (hmac, hashlib,
secrets): the MACs of the HMAC-SHA256 challenge-response and the key file rules, the same as
proto/auth_mac.c.

    client -> AUTH HMAC_CHALLENGE, token Nc (32 random bytes)
    server <- HMAC_CHALLENGE, token Ns (32 random bytes)
    client -> AUTH HMAC_PROOF, token HMAC-SHA256(K, Ns || Nc || b"deformd-auth-v1 client")
    server <- HMAC_PROOF, token HMAC-SHA256(K, Ns || Nc || b"deformd-auth-v1 server"), checked
"""
import hashlib
import hmac
import os
import stat

from .schema import (AUTH_CONTEXT_CLIENT, AUTH_CONTEXT_SERVER, AUTH_MAC_BYTES,
                     AUTH_NONCE_BYTES)

KEY_MIN_BYTES = 32      # DF_AUTH_KEY_MIN_BYTES
KEY_CAP_BYTES = 1024    # DF_AUTH_KEY_CAP_BYTES


class AuthError(Exception):
    """The key cannot be used (key file rules) or the server failed to prove it knows the key."""


def mac(key: bytes, server_nonce: bytes, client_nonce: bytes, role: str) -> bytes:
    """HMAC-SHA256(key, server_nonce || client_nonce || context of role "client" / "server")."""
    if len(server_nonce) != AUTH_NONCE_BYTES or len(client_nonce) != AUTH_NONCE_BYTES:
        raise ValueError("nonces are %d bytes" % AUTH_NONCE_BYTES)
    ctx = {"client": AUTH_CONTEXT_CLIENT, "server": AUTH_CONTEXT_SERVER}[role]
    out = hmac.new(bytes(key), server_nonce + client_nonce + ctx, hashlib.sha256).digest()
    assert len(out) == AUTH_MAC_BYTES
    return out


def verify(expected: bytes, got: bytes) -> bool:
    """Constant-time comparison of two MACs."""
    return hmac.compare_digest(expected, got)


def load_key(path: str) -> bytes:
    """The key in the file at `path`: its bytes without trailing blanks, tabs, CR, LF; 32..1024
    bytes; the file must be regular and neither readable nor writable by others."""
    with open(path, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode):
            raise AuthError("key file %s: not a regular file" % path)
        if st.st_mode & (stat.S_IROTH | stat.S_IWOTH):
            raise AuthError("key file %s: readable or writable by others (mode %04o): chmod 600 it"
                            % (path, st.st_mode & 0o7777))
        data = f.read(KEY_CAP_BYTES + 256)
    key = data.rstrip(b" \t\r\n")
    if len(key) < KEY_MIN_BYTES:
        raise AuthError("key file %s: key of %d bytes is too short (at least %d)"
                        % (path, len(key), KEY_MIN_BYTES))
    if len(key) > KEY_CAP_BYTES:
        raise AuthError("key file %s: key longer than %d bytes" % (path, KEY_CAP_BYTES))
    return key
