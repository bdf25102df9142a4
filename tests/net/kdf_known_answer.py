#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# The known answers of SecureKey.MatchesTheArgon2ReferenceImplementation
# (tests/net/secure_transport_test.cpp), computed without pliant or libsodium: the salt with
# Python's BLAKE2b, the key with the Argon2 reference implementation (Debian's libargon2-1,
# through ctypes), as docs/protocol.md section 10.1 defines them: Argon2id, one lane, 32 bytes,
# salt = BLAKE2b-128("pliant/salt/v1" + context). Run: python3 tests/net/kdf_known_answer.py
import ctypes, hashlib
lib = ctypes.CDLL("libargon2.so.1")
f = lib.argon2id_hash_raw
f.argtypes = [ctypes.c_uint32, ctypes.c_uint32, ctypes.c_uint32, ctypes.c_char_p, ctypes.c_size_t,
              ctypes.c_char_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t]
def key(pw, ctx, t, m_bytes):
    salt = hashlib.blake2b(b"pliant/salt/v1" + ctx, digest_size=16).digest()
    out = ctypes.create_string_buffer(32)
    rc = f(t, m_bytes // 1024, 1, pw, len(pw), salt, len(salt), out, 32)
    assert rc == 0, rc
    return salt.hex(), out.raw.hex()
for passes, memory in ((2, 64 << 20), (1, 8192)):  # the protocol's limits; the tests' cheapest
    print(passes, memory, *key(b"open sesame", b"pliant session v1", passes, memory))
