"""The Python decoders replay every seed of the C fuzzer's corpus (tests/fuzz/corpus/proto, one
valid frame per sample message, written by tests/fuzz/gen_proto_corpus.c) and re-encode each to
identical bytes, the oracle fuzz_proto.c applies to the C codecs: header and body, with the body
chosen by (type, flags) as df_msg_body_kind does. Every body of PROTOCOL.md section 4 has a
Python codec (deformd_client.bodies), and every one is exercised by some seed."""
import os
import random

import pytest

from deformd_client import ProtocolError, bodies, frame as fr, schema

ROOT = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))
CORPUS = os.path.join(ROOT, "tests", "fuzz", "corpus", "proto")
SEEDS = sorted(f for f in os.listdir(CORPUS) if not f.startswith("."))


def test_corpus_is_there():
    assert len(SEEDS) >= 30, SEEDS


@pytest.mark.parametrize("seed", SEEDS)
def test_seed_decodes_and_reencodes_identically(seed):
    data = open(os.path.join(CORPUS, seed), "rb").read()
    d = fr.FrameDecoder()
    frames = d.feed(data)
    assert len(frames) == 1, "%s: %d frames" % (seed, len(frames))
    f = frames[0]
    head = fr.encode_header(f.type, f.flags, f.request_id, len(f.payload))
    assert head == data[:fr.HEADER_SIZE], seed
    name, obj = bodies.decode_frame_body(f.type, f.flags, f.payload)
    again = bodies.encode_body(name, obj)
    assert again == bytes(f.payload), "%s: body %s re-encodes to different bytes" % (seed, name)
    assert fr.encode_frame(f.type, again, f.request_id, f.flags) == data


def test_every_body_has_a_codec_and_a_seed():
    named = {b for bs in schema.BODIES.values() for b in bs if b} | {"error"}
    assert named == set(bodies.BODY_CODECS), named ^ set(bodies.BODY_CODECS)
    seen = set()
    for seed in SEEDS:
        for f in fr.FrameDecoder().feed(open(os.path.join(CORPUS, seed), "rb").read()):
            seen.add(schema.body_of(f.type, f.flags))
    # error bodies and the empty body are not in the corpus: round-trip them here
    for name, obj in (("error", (-7, "no session 12")), ("empty", None)):
        assert bodies.encode_body(name, bodies.decode_body(name, bodies.encode_body(name, obj))) \
            == bodies.encode_body(name, obj)
        seen.add(name)
    assert seen == named, named - seen


@pytest.mark.parametrize("seed", SEEDS)
def test_every_cut_of_a_seed_is_refused_or_reencodes(seed):
    """The fuzzer's oracle on each prefix of the payload: a decoder either refuses it with
    ProtocolError (never another exception) or accepts it, and then it re-encodes to exactly
    those bytes (a load_reply without its optional report, say)."""
    f = fr.FrameDecoder().feed(open(os.path.join(CORPUS, seed), "rb").read())[0]
    name = schema.body_of(f.type, f.flags)
    payload = bytes(f.payload)
    for n in range(len(payload)):
        try:
            obj = bodies.decode_body(name, payload[:n])
        except ProtocolError:
            continue
        assert bodies.encode_body(name, obj) == payload[:n], "%s cut at %d" % (seed, n)


@pytest.mark.parametrize("seed", SEEDS)
def test_every_decoder_on_every_seed(seed):
    """Step 2 of fuzz_proto.c: every body decoder runs on the whole seed (header included) and
    on its payload; each refuses with ProtocolError or accepts bytes it re-encodes exactly."""
    data = open(os.path.join(CORPUS, seed), "rb").read()
    for blob in (data, data[fr.HEADER_SIZE:]):
        for name in bodies.BODY_CODECS:
            try:
                obj = bodies.decode_body(name, blob)
            except ProtocolError:
                continue
            assert bodies.encode_body(name, obj) == blob, "%s as %s" % (seed, name)


@pytest.mark.parametrize("seed", SEEDS)
def test_fixed_seed_mutations(seed):
    """A short deterministic fuzz run (random.Random(1), like the fuzz step's -seed=1 run): 200
    copies of the payload with 1..4 bytes overwritten, through every decoder: each is refused with
    ProtocolError (no other exception) or re-encodes exactly. Error messages are the one
    exception to exactness: their bytes that are not UTF-8 read as U+FFFD (they are shown)."""
    rng = random.Random("%s:1" % seed)
    data = bytes(fr.FrameDecoder().feed(open(os.path.join(CORPUS, seed), "rb").read())[0].payload)
    for _ in range(200):
        b = bytearray(data)
        for _ in range(rng.randint(1, 4)):
            if b:
                b[rng.randrange(len(b))] = rng.randrange(256)
        b = bytes(b)
        for name in bodies.BODY_CODECS:
            try:
                obj = bodies.decode_body(name, b)
            except ProtocolError:
                continue
            again = bodies.encode_body(name, obj)
            if name == "error" and again != b:
                try:
                    b[6:].decode("utf-8")
                except UnicodeDecodeError:
                    continue
            assert again == b, "%s mutated, as %s: %s" % (seed, name, b.hex())
