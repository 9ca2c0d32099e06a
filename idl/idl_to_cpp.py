#!/usr/bin/env python3
"""Generates the project's C++ message types from the OMG IDL files in idl/.

The IDL is the single source of truth. For every @final struct this writes a plain C++ struct
(rslam::msg::Image, ...), its XCDR1 serialisation (common/bus/cdr.h), the reading of its key
fields, and MessageTraits (DDS type name, IDL text for recordings). It reads the subset of
IDL 4 the project uses: modules, enums, @final structs, @key members, primitive types,
string and sequence<T>.

usage: idl_to_cpp.py OUT_DIR IDL_ROOT FILE.idl [FILE.idl ...]
writes OUT_DIR/rslam/msg/<file>.h per IDL file and OUT_DIR/rslam/msg/all_messages.h
"""
import os
import re
import sys

PRIMITIVES = {
    "boolean": ("bool", 1), "octet": ("uint8_t", 1), "char": ("char", 1),
    "int8": ("int8_t", 1), "uint8": ("uint8_t", 1), "int16": ("int16_t", 2),
    "uint16": ("uint16_t", 2), "int32": ("int32_t", 4), "uint32": ("uint32_t", 4),
    "int64": ("int64_t", 8), "uint64": ("uint64_t", 8), "float": ("float", 4),
    "double": ("double", 8), "string": ("std::string", 4),
}


class IdlError(Exception):
    pass


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def tokenize(text):
    return re.findall(r"@\w+|::|[A-Za-z_]\w*|\d+|[{}<>;,]", text)


class Parser:
    def __init__(self, path, text):
        self.path = path
        body = "\n".join(l for l in strip_comments(text).splitlines() if not l.strip().startswith("#"))
        self.toks = tokenize(body)
        self.i = 0
        self.structs = []   # (qualified name, [(type, name, is_key)])
        self.enums = []     # (qualified name, [enumerators])

    def peek(self):
        return self.toks[self.i] if self.i < len(self.toks) else None

    def take(self, expected=None):
        tok = self.peek()
        if tok is None or (expected and tok != expected):
            raise IdlError(f"{self.path}: expected {expected or 'a token'}, got {tok}")
        self.i += 1
        return tok

    def parse(self, scope=()):
        while self.peek() not in (None, "}"):
            annotations = []
            while self.peek() and self.peek().startswith("@"):
                annotations.append(self.take())
            kw = self.take()
            if kw == "module":
                name = self.take()
                self.take("{")
                self.parse(scope + (name,))
                self.take("}")
                self.take(";")
            elif kw == "enum":
                name = self.take()
                self.take("{")
                values = []
                while self.peek() != "}":
                    values.append(self.take())
                    if self.peek() == ",":
                        self.take()
                self.take("}")
                self.take(";")
                self.enums.append(("::".join(scope + (name,)), values))
            elif kw == "struct":
                if "@final" not in annotations:
                    raise IdlError(f"{self.path}: struct {self.peek()} must be @final (XCDR1 interop)")
                name = self.take()
                self.take("{")
                members = []
                while self.peek() != "}":
                    is_key = False
                    while self.peek().startswith("@"):
                        is_key |= self.take() == "@key"
                    mtype = self.parse_type()
                    mname = self.take()
                    self.take(";")
                    members.append((mtype, mname, is_key))
                self.take("}")
                self.take(";")
                self.structs.append(("::".join(scope + (name,)), members))
            else:
                raise IdlError(f"{self.path}: unsupported construct '{kw}'")

    def parse_type(self):
        tok = self.take()
        if tok == "sequence":
            self.take("<")
            inner = self.parse_type()
            self.take(">")
            return ("seq", inner)
        if tok == "unsigned":
            tok = "u" + {"short": "int16", "long": "int32"}[self.take()]
        return ("name", tok)


def cpp_type(t):
    if t[0] == "seq":
        return f"std::vector<{cpp_type(t[1])}>"
    name = t[1]
    return PRIMITIVES[name][0] if name in PRIMITIVES else name.split("::")[-1]


def is_primitive(t):
    return t[0] == "name" and t[1] in PRIMITIVES and t[1] != "string"


def generate(out_dir, idl_root, idl_files):
    parsed = {}
    for path in idl_files:
        with open(path) as f:
            text = f.read()
        p = Parser(path, text)
        p.parse()
        includes = re.findall(r'#include\s+"([^"]+)"', text)
        parsed[path] = (p, includes, text)

    enums = {}
    structs = {}
    for p, _, _ in parsed.values():
        for name, values in p.enums:
            enums[name.split("::")[-1]] = values
        for name, members in p.structs:
            structs[name.split("::")[-1]] = members

    def idl_text_of(path, seen):
        """The file's IDL with its includes inlined once, as a self-contained schema."""
        p, includes, text = parsed[path]
        out = ""
        for inc in includes:
            inc_path = os.path.join(idl_root, inc)
            if inc_path not in seen:
                seen.add(inc_path)
                out += idl_text_of(inc_path, seen)
        body = "\n".join(l for l in text.splitlines() if not l.strip().startswith("#include"))
        return out + body.strip() + "\n"

    def key_members(sname):
        return [(t, n) for t, n, k in structs[sname] if k]

    def has_key(sname):
        return bool(key_members(sname))

    os.makedirs(os.path.join(out_dir, "rslam", "msg"), exist_ok=True)
    headers = []
    for path in idl_files:
        p, includes, _ = parsed[path]
        base = os.path.splitext(os.path.basename(path))[0]
        headers.append(base)
        lines = [
            f"// Generated from idl/{os.path.relpath(path, idl_root)} by idl/idl_to_cpp.py. Do not edit.",
            "#pragma once",
            "",
            "#include <cstdint>",
            "#include <string>",
            "#include <vector>",
            "",
            '#include "common/bus/cdr.h"',
            '#include "common/bus/message_traits.h"',
        ]
        for inc in includes:
            lines.append(f'#include "rslam/msg/{os.path.splitext(os.path.basename(inc))[0]}.h"')
        lines += ["", "namespace rslam::msg {", ""]
        for name, values in p.enums:
            short = name.split("::")[-1]
            lines.append(f"enum class {short} : int32_t {{")
            for i, v in enumerate(values):
                lines.append(f"  {v} = {i},")
            lines.append("};")
            lines.append(f"inline constexpr int32_t k{short}Count = {len(values)};")
            lines.append(f"inline const char* ToString({short} v) {{")
            lines.append("  switch (v) {")
            for v in values:
                lines.append(f'    case {short}::{v}: return "{v}";')
            lines.append("  }")
            lines.append('  return "?";')
            lines.append("}")
            lines.append("")
        schema = idl_text_of(path, {path})
        for name, members in p.structs:
            short = name.split("::")[-1]
            lines.append(f"struct {short} {{")
            for t, n, _ in members:
                init = " = {}" if (t[0] == "name" and (t[1] in PRIMITIVES and t[1] != "string" or t[1].split('::')[-1] in enums)) else ""
                lines.append(f"  {cpp_type(t)} {n}{init};")
            lines.append(f"  bool operator==(const {short}&) const = default;")
            lines.append("};")
            lines.append("")
            # Serialize
            lines.append(f"inline void Serialize(bus::CdrWriter& w, const {short}& v) {{")
            for t, n, _ in members:
                lines.append("  " + write_stmt(t, f"v.{n}", enums))
            lines.append("}")
            lines.append(f"inline void Deserialize(bus::CdrReader& r, {short}& v) {{")
            for t, n, _ in members:
                lines.append("  " + read_stmt(t, f"v.{n}", enums, structs))
            lines.append("}")
            # FillExample: distinct non-default values in every field, for round-trip tests.
            lines.append(f"inline void FillExample({short}& v, int seed) {{")
            for i, (t, n, _) in enumerate(members):
                lines.append("  " + fill_stmt(t, f"v.{n}", f"seed + {i + 1}", enums))
            lines.append("}")
            # Key fields: ReadKeyFields stops after the last key field (enough at the end of a
            # message); ReadAllKeyFields consumes the whole struct (a key struct followed by more).
            keyed = has_key(short)
            for fn, upto in (("ReadKeyFields", True), ("ReadAllKeyFields", False)):
                lines.append(f"inline void {fn}(bus::CdrReader& r, [[maybe_unused]] bus::CdrKeyWriter& k, {short}*) {{")
                last = max([i for i, (_, _, kk) in enumerate(members) if kk], default=-1)
                end = last + 1 if upto else len(members)
                for i, (t, n, kk) in enumerate(members[:end]):
                    ct = cpp_type(t)
                    if kk and t[0] == "name" and t[1].split("::")[-1] in structs:
                        nested = "ReadKeyFields" if (upto and i == last) else "ReadAllKeyFields"
                        lines.append(f"  {nested}(r, k, static_cast<{ct}*>(nullptr));")
                    elif kk:
                        lines.append(f"  {{ {ct} f; {read_stmt(t, 'f', enums, structs)} k.Write(f); }}")
                    else:
                        lines.append(f"  {{ {ct} f; {read_stmt(t, 'f', enums, structs)} }}")
                lines.append("}")
            lines.append("")
        # MessageTraits for top-level message types (those with a Header member).
        for name, members in p.structs:
            short = name.split("::")[-1]
            if not any(t == ("name", "Header") for t, _, _ in members):
                continue
            lines.append("}  // namespace rslam::msg")
            lines.append("")
            lines.append("namespace rslam::bus {")
            lines.append("template <>")
            lines.append(f"struct MessageTraits<msg::{short}> {{")
            lines.append(f'  static constexpr const char* kTypeName = "{name}";')
            lines.append(f"  static constexpr bool kKeyed = {'true' if has_key(short) else 'false'};")
            esc = schema.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
            lines.append(f'  static constexpr const char* kIdl = "{esc}";')
            lines.append("};")
            lines.append("}  // namespace rslam::bus")
            lines.append("")
            lines.append("namespace rslam::msg {")
            lines.append("")
        lines.append("}  // namespace rslam::msg")
        write_if_changed(os.path.join(out_dir, "rslam", "msg", base + ".h"), "\n".join(lines) + "\n")

    # all_messages.h: every header plus the list of top-level message types.
    tops = []
    for path in idl_files:
        for name, members in parsed[path][0].structs:
            if any(t == ("name", "Header") for t, _, _ in members):
                tops.append(name.split("::")[-1])
    lines = ["// Generated by idl/idl_to_cpp.py. Do not edit.", "#pragma once", ""]
    lines += [f'#include "rslam/msg/{h}.h"' for h in headers]
    lines += ["", "// X-macro over every top-level message type: RSLAM_FOR_EACH_MESSAGE(M) expands M(Type).",
              "#define RSLAM_FOR_EACH_MESSAGE(M) \\"]
    lines += [f"  M({t}) \\" for t in tops]
    lines += ["", ""]
    write_if_changed(os.path.join(out_dir, "rslam", "msg", "all_messages.h"), "\n".join(lines))


def write_stmt(t, expr, enums):
    if t[0] == "seq":
        inner = t[1]
        if is_primitive(inner) and inner[1] != "boolean":
            return f"w.WritePrimitiveSequence({expr});"
        return (f"w.Write<uint32_t>(static_cast<uint32_t>({expr}.size())); "
                f"for (const auto& e : {expr}) {{ {write_stmt(inner, 'e', enums)} }}")
    name = t[1].split("::")[-1]
    if t[1] in PRIMITIVES or name in enums:
        return f"w.Write({expr});"
    return f"Serialize(w, {expr});"


def read_stmt(t, expr, enums, structs):
    if t[0] == "seq":
        inner = t[1]
        if is_primitive(inner) and inner[1] != "boolean":
            return f"r.ReadPrimitiveSequence({expr});"
        return (f"{expr}.resize(r.ReadCount(1)); "
                f"for (auto& e : {expr}) {{ {read_stmt(inner, 'e', enums, structs)} }}")
    name = t[1].split("::")[-1]
    if name in enums:
        return f"r.ReadEnum({expr}, k{name}Count);"
    if t[1] in PRIMITIVES:
        return f"r.Read({expr});"
    if name in structs:
        return f"Deserialize(r, {expr});"
    raise IdlError(f"unknown type {t[1]}")


def fill_stmt(t, expr, seed, enums):
    if t[0] == "seq":
        return (f"{expr}.resize(3); for (int j = 0; j < 3; ++j) {{ "
                f"{fill_stmt(t[1], expr + '[j]', '(' + seed + ') * 7 + j', enums)} }}")
    name = t[1].split("::")[-1]
    if name in enums:
        return f"{expr} = static_cast<{name}>(({seed}) % k{name}Count);"
    if t[1] == "string":
        # append, not operator+: GCC 12 warns -Wrestrict on "s" + std::string (a false positive)
        return f'{expr} = std::string("s").append(std::to_string({seed}));'
    if t[1] == "boolean":
        return f"{expr} = ({seed}) % 2 == 1;"
    if t[1] in PRIMITIVES:
        return f"{expr} = static_cast<{PRIMITIVES[t[1]][0]}>({seed});"
    return f"FillExample({expr}, {seed});"


def write_if_changed(path, text):
    if os.path.exists(path):
        with open(path) as f:
            if f.read() == text:
                return
    with open(path, "w") as f:
        f.write(text)


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    try:
        generate(sys.argv[1], sys.argv[2], sys.argv[3:])
    except IdlError as e:
        sys.exit(f"idl_to_cpp: {e}")
