#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
"""Rejects any #include that breaks the module dependency table of docs/style.md §2.

Checks include/pliant/<m>/, src/<m>/, tests/<m>/ and apps/. Prints one line per violation
(file:line: module 'a' may not include 'b') and exits 1 if there is any.
"""
import pathlib
import re
import sys

ALLOWED = {
    "core": set(),
    "mesh": {"core"},
    "remesh": {"core", "mesh"},
    "subdiv": {"core"},
    "sim": {"core"},
    "net": {"core"},
    "session": {"core", "sim", "subdiv", "net"},
    "render": {"core"},
}
# Third-party headers a module may not use (only the viewer, apps/pliant-cli/viewer/, links GLFW/ImGui, only render GL,
# only net's ENet adapter includes ENet, only net's secure layer and mesh's glTF index check (its
# base64 decoder) include libsodium, only net's quantised-value packing includes zstd).
FORBIDDEN_THIRD_PARTY = {
    "GLFW/": lambda path: path.parts[:3] == ("apps", "pliant-cli", "viewer"),
    "imgui": lambda path: path.parts[:3] == ("apps", "pliant-cli", "viewer"),
    "enet/": lambda path: path.as_posix() == "src/net/enet_transport.cpp",
    "sodium": lambda path: path.as_posix()
    in ("src/net/secure_transport.cpp", "src/mesh/gltf_indices.cpp"),
    "zstd": lambda path: path.as_posix() == "src/net/quantised.cpp",
}
PLIANT_INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]pliant/([a-z_]+)/')
SRC_INCLUDE = re.compile(r'^\s*#\s*include\s*[<"](?:\.\./)*(?:src/)?([a-z_]+)/[a-z_]+_internal\.h')
ANY_INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]')


def module_of(path: pathlib.Path):
    parts = path.parts
    if parts[0] == "include" and len(parts) > 2:
        return parts[2]
    if parts[0] in ("src", "tests") and len(parts) > 1 and parts[1] in ALLOWED:
        return parts[1]
    return None


def main() -> int:
    root = pathlib.Path(__file__).resolve().parent.parent
    bad = []
    for folder in ("include", "src", "tests", "apps", "bench", "fuzz", "examples"):
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in (".h", ".hpp", ".cpp", ".cc"):
                continue
            rel = path.relative_to(root)
            mod = module_of(rel)
            is_test = rel.parts[0] == "tests"
            for lineno, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
                m = PLIANT_INCLUDE.match(line)
                if m and mod is not None:
                    target = m.group(1)
                    if target != mod and target not in ALLOWED[mod] and not is_test:
                        bad.append(f"{rel}:{lineno}: module '{mod}' may not include '{target}'")
                m = ANY_INCLUDE.match(line)
                if m:
                    header = m.group(1)
                    # private headers of another module's src/ (apps and other modules never)
                    if header.endswith("_internal.h") and "/" in header:
                        owner = header.split("/")[-2]
                        if owner in ALLOWED and owner != mod:
                            bad.append(f"{rel}:{lineno}: '{header}' is private to module '{owner}'")
                    for prefix, may in FORBIDDEN_THIRD_PARTY.items():
                        if header.startswith(prefix) and not may(rel) and not is_test:
                            bad.append(f"{rel}:{lineno}: only its owner may include '{header}'")
    for line in bad:
        print(line)
    if bad:
        print(f"check_includes: {len(bad)} include(s) break the dependency rules "
              "(docs/style.md §2)")
        return 1
    print("check_includes: all includes follow the dependency rules")
    return 0


if __name__ == "__main__":
    sys.exit(main())
