#!/usr/bin/python3
"""Every tolerance of a test is a named constant that says why it has its size (issue 15).

  tolerance_check.py REPO_ROOT

Scans every tracked .cc file under tests/ for EXPECT_NEAR / ASSERT_NEAR calls whose third argument,
the tolerance, is a bare numeric literal: `1e-9`, `-1e-9`, `0.005`, `.5`, `0x1p-52`, `1'000.0f`, also
inside parentheses. The call's arguments are split at the commas of bracket depth one, across lines;
comments, string and character literals are skipped, so a call written in a comment does not count.
A tolerance written as an expression (`sigma_w * kRelativeTolerance`, `4 * sd`) is left to review.
Lists every offender as FILE:LINE; exit 1 when there is one. To fix one, give the value a name near
the top of the file or of the test, `constexpr double kWhyTolerance = 1e-9;  // why this size`
(docs/reliability.md, §10).
"""
import pathlib
import re
import subprocess
import sys

root = pathlib.Path(sys.argv[1]).resolve()
tracked = subprocess.run(["git", "-C", str(root), "ls-files", "--", "tests"], capture_output=True, text=True)
if tracked.returncode == 0:
    files = sorted(name for name in tracked.stdout.split() if name.endswith(".cc"))
else:  # not a git checkout (an exported tree): every file on disk
    files = sorted(str(p.relative_to(root)) for p in (root / "tests").rglob("*.cc"))
if not files:
    print("named tolerances: no .cc file found under tests/")
    sys.exit(1)

RAW_PREFIXES = ("R", "u8R", "uR", "UR", "LR")


def blank_comments_and_literals(text):
    """`text` with every comment and the body of every string or character literal replaced by spaces
    (newlines kept), so that offsets and line numbers stay those of the source."""
    out = list(text)
    i, n = 0, len(text)

    def blank(start, end):
        for k in range(start, min(end, n)):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = text[i]
        if text.startswith("//", i):
            end = text.find("\n", i)
            end = n if end < 0 else end
            blank(i, end)
            i = end
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            blank(i, end)
            i = end
        elif c in "\"'":
            w = i  # the identifier or number just before the quote
            while w > 0 and (text[w - 1].isalnum() or text[w - 1] in "_'."):
                w -= 1
            word = text[w:i]
            if c == "'" and word[:1].isdigit():
                i += 1  # a digit separator: 1'000
                continue
            if c == '"' and word in RAW_PREFIXES:
                open_paren = text.find("(", i + 1)
                delimiter = text[i + 1:open_paren] if open_paren >= 0 else ""
                end = text.find(")" + delimiter + '"', open_paren + 1) if open_paren >= 0 else -1
                end = n if end < 0 else end + len(delimiter) + 2
                blank(i, end)
                i = end
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            blank(i, j + 1)
            i = j + 1
        else:
            i += 1
    return "".join(out)


# A C++ preprocessing number (every integer and floating literal, with its exponent sign, digit separators
# and suffix), with optional unary signs and enclosing parentheses.
PP_NUMBER = r"\.?\d(?:[eEpP][+-]|'[0-9A-Za-z_]|[0-9A-Za-z_.])*"
LITERAL = re.compile(r"\s*(?:[(+-]\s*)*(" + PP_NUMBER + r")\s*(?:\)\s*)*")
CALL = re.compile(r"(?<![\w])((?:EXPECT|ASSERT)_NEAR)\s*\(")


def arguments(code, start):
    """The top-level arguments of the call whose '(' ends just before `start`, or None if it never closes."""
    depth, args, begin = 1, [], start
    for i in range(start, len(code)):
        c = code[i]
        if c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
            if depth == 0:
                args.append(code[begin:i])
                return args
        elif c == "," and depth == 1:
            args.append(code[begin:i])
            begin = i + 1
    return None


offenders, calls = [], 0
for name in files:
    source = (root / name).read_text(errors="replace")
    code = blank_comments_and_literals(source)
    for m in CALL.finditer(code):
        args = arguments(code, m.end())
        if args is None or len(args) != 3:
            continue
        calls += 1
        literal = LITERAL.fullmatch(args[2])
        if literal:
            line = code.count("\n", 0, m.start()) + 1
            offenders.append(f"{name}:{line}: {m.group(1)} with the literal tolerance {args[2].strip()}: name it "
                             f"(a constexpr with the reason for its size; docs/reliability.md §10)")

if offenders:
    for o in offenders:
        print(o)
    print(f"{len(offenders)} of {calls} EXPECT_NEAR/ASSERT_NEAR calls in tests/ have a literal tolerance")
    sys.exit(1)
print(f"named tolerances: {calls} EXPECT_NEAR/ASSERT_NEAR calls in the {len(files)} .cc files of tests/, none with a literal "
      f"tolerance")
