#!/usr/bin/env python3
"""Finds names that would collide in a unity build, before a compiler does.

CI and the sanitizer builds compile each target's sources in unity batches (one translation
unit per batch of files). Two sources of one target that each define the same name with internal
linkage (in an anonymous namespace, or `static` at file scope) then fail with "redefinition of".
Which files share a batch shifts whenever a source is added, so this check looks at every pair of
sources of a target, not only today's batches.

Targets and their sources are read from the CMake files: the globbed libraries (src/core/**,
src/ros, src/sim) and every add_library / add_executable / gmm_add_tool / catkin_add_gtest call
that names several .cpp files. Names are found by a line-based reading of the code base's own
layout (clang-format: declarations of a namespace start at column 0): functions (a name and
its parameter text, so overloads of other parameters pass), variables and constants, types, and
aliases (with their type: an alias repeated for the same type is allowed). Exit status 1 with each collision named, 0 when there is none.
"""
import pathlib
import re
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent

CALL = re.compile(r"\b(add_library|add_executable|gmm_add_tool|catkin_add_gtest)\s*\(([^)]*)\)", re.S)
SOURCE = re.compile(r"[\w/.${}-]+\.cpp")
SKIP_START = ("}", "//", "#", "template", "namespace", "using namespace", "extern", "friend")
TYPE_DEF = re.compile(r"^(?:struct|class|enum(?: class)?|union)\s+(\w+)\s*(?:final\s*)?[:{]")
ALIAS = re.compile(r"^using\s+(\w+)\s*=")
FUNCTION = re.compile(r"([~\w]+)\s*\(([^()]*(?:\([^()]*\)[^()]*)*)\)?")
VARIABLE = re.compile(r"(\w+)\s*(?:\[[^\]]*\])?\s*(?:=|\{|;)")


def targets():
    """{target: [source paths relative to the repository]}"""
    found = {
        "gmm_core": sorted(p.relative_to(REPO).as_posix() for p in (REPO / "src/core").rglob("*.cpp")),
        "gmm_ros": sorted(p.relative_to(REPO).as_posix() for p in (REPO / "src/ros").glob("*.cpp")),
        "gmm_sim": sorted(p.relative_to(REPO).as_posix() for p in (REPO / "src/sim").glob("*.cpp")),
    }
    for cmake in sorted((REPO / "cmake").rglob("*.cmake")) + [REPO / "CMakeLists.txt"]:
        text = re.sub(r"#[^\n]*", "", cmake.read_text())
        for _, args in CALL.findall(text):
            words = args.split()
            sources = [s.replace("${CMAKE_CURRENT_SOURCE_DIR}/", "") for s in SOURCE.findall(args)]
            sources = [s for s in sources if "$" not in s and (REPO / s).is_file()]
            if words and len(sources) > 1:
                found.setdefault(words[0], sorted(set(sources)))
    return found


def internal_names(path):
    """(key, line) of every internal-linkage definition at namespace level in one source."""
    names = []
    depth = 0  # braces opened since the file's start, by lines
    anonymous_depths = []  # depth inside each open anonymous namespace
    for number, raw in enumerate((REPO / path).read_text().splitlines(), 1):
        line = re.sub(r"//.*", "", raw).rstrip()
        line = re.sub(r'"(?:\\.|[^"\\])*"', '""', line)
        stripped = line.strip()
        at_namespace_level = not raw.startswith((" ", "\t")) and stripped and not raw.startswith("}")
        if stripped.startswith("namespace {"):
            anonymous_depths.append(depth + 1)
        elif at_namespace_level and not stripped.startswith(SKIP_START):
            inside = bool(anonymous_depths) and depth == anonymous_depths[-1]
            if inside or stripped.startswith("static "):
                key = declared(stripped)
                if key:
                    names.append((key, number))
        depth += line.count("{") - line.count("}")
        while anonymous_depths and depth < anonymous_depths[-1]:
            anonymous_depths.pop()
    return names


def declared(text):
    text = re.sub(r"^(?:static|inline|constexpr|const|thread_local|\s)+", "", text)
    match = TYPE_DEF.match(text)
    if match:
        return match.group(1)
    match = ALIAS.match(text)
    if match:  # "Clock=std::chrono::steady_clock": allowed again for the same type
        return match.group(1) + "=" + re.sub(r"\s+", "", text.split("=", 1)[1])
    if text.startswith("using "):
        return None  # a using-declaration may be repeated
    before_equals = text.split("=")[0]
    call = FUNCTION.search(before_equals)
    if call and "(" in before_equals:
        return "%s(%s)" % (call.group(1), re.sub(r"\s+", " ", call.group(2)).strip())
    variable = VARIABLE.search(text)
    return variable.group(1) if variable else None


def main():
    collisions = []
    for target, sources in sorted(targets().items()):
        seen = {}
        for source in sources:
            for key, line in internal_names(source):
                name, is_alias = key.split("=")[0], "=" in key
                first = seen.setdefault(name, (source, line, key))
                same_alias = is_alias and first[2] == key
                if first[0] != source and not same_alias:
                    collisions.append((target, name, first[:2], (source, line)))
    for target, key, (first, first_line), (second, second_line) in collisions:
        print("check_unity_names: %s: '%s' is defined in %s:%d and %s:%d; a unity batch of the "
              "target fails on it (share one definition in a header, or rename one)"
              % (target, key, first, first_line, second, second_line))
    if collisions:
        return 1
    print("check_unity_names: %d targets, no internal name defined twice in one target"
          % len(targets()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
