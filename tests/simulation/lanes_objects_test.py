#!/usr/bin/python3
"""The objects of the open loop's (or the landing's) lanes keep the instruction sets apart
(engine/simulation/lanes.h):

  lanes_objects_test.py LIBRARY [PREFIX]   (libgesweep_simulation.a, open_loop_lanes; or
                                            libgesweep_control.a, landing_lanes: the landing's lanes)

1. Every symbol that open_loop_lanes_avx2.cc.o or open_loop_lanes_avx512.cc.o defines for the linker
   (global or weak) names its own architecture (xsimd::avx2, xsimd::avx512f). A weak symbol that does
   not, an inline function compiled with -mavx2 say, could be the copy the linker keeps for the whole
   program, and fault on a CPU without AVX2. Except DW.ref.__gxx_personality_v0, the compiler's
   pointer to the C++ exception personality routine (data, the same in every object; the sanitized
   build emits it).
2. No object of the library holds a fused multiply-add (vfmadd..., vfmsub..., vfnmadd..., vfnmsub...):
   the lanes are bit for bit the scalar code only without them.
3. Each architecture's object uses its registers (ymm, zmm): its flags took effect.

Lists every offender; exit 1 when there is one.
"""
import re
import subprocess
import sys

library = sys.argv[1]
prefix = sys.argv[2] if len(sys.argv) > 2 else "open_loop_lanes"
architectures = {f"{prefix}_avx2.cc.o": ("xsimd::avx2", "%ymm"),
                 f"{prefix}_avx512.cc.o": ("xsimd::avx512f", "%zmm")}
problems = []

# nm -A: "library:member:address type name" (no address for undefined symbols, left out here).
nm = subprocess.run(["nm", "-A", "-C", "--defined-only", library], check=True, capture_output=True, text=True)
seen = {member: 0 for member in architectures}
for line in nm.stdout.splitlines():
    location, _, rest = line.partition(" ")
    member = location.split(":")[-2] if location.count(":") >= 2 else ""
    if member not in architectures:
        continue
    kind, _, name = rest.partition(" ")
    if kind not in "TWVDBRuvwi" or kind == "":  # local symbols (t, d, b, r) stay in their object
        continue
    if name == "DW.ref.__gxx_personality_v0":  # a pointer to libstdc++'s routine: data, no code of ours
        continue
    seen[member] += 1
    arch = architectures[member][0]
    if arch not in name:
        problems.append(f"{member}: {kind} {name}: a symbol the linker may share, without {arch} in its name")
for member, count in seen.items():
    if count == 0:
        problems.append(f"{member}: no kernel defined (is it in {library}?)")

disassembly = subprocess.run(["objdump", "-d", "--no-show-raw-insn", library], check=True, capture_output=True,
                             text=True).stdout
fused = re.compile(r"\bv?f(n?m(add|sub)|maddsub|msubadd)\w*\b")
member = ""
registers = {m: False for m in architectures}
for line in disassembly.splitlines():
    header = re.match(r"^(\S+\.o):\s+file format", line)
    if header:
        member = header.group(1)
        continue
    if "\t" not in line:
        continue
    instruction = line.split("\t", 1)[1]
    if fused.search(instruction.split(" ", 1)[0]):
        problems.append(f"{member}: fused multiply-add: {instruction.strip()}")
    if member in architectures and architectures[member][1] in instruction:
        registers[member] = True
for member, used in registers.items():
    if not used:
        problems.append(f"{member}: no {architectures[member][1]} register: built without its flags?")

if problems:
    print(f"{len(problems)} problems in {library}:")
    for p in problems:
        print("  " + p)
    sys.exit(1)
print(f"{library}: the AVX2 and AVX-512 kernels define only their own symbols ({sum(seen.values())}), "
      "and no object has a fused multiply-add")
