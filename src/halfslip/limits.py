"""Every size limit on what halfslip reads, in one place (docs/interface.md, "Limits").

An input past a limit is refused before anything of its size is allocated,
with a one-line :class:`~halfslip.errors.HalfslipInputError` that says the
size found, the limit and, for runs and sweeps, the memory estimate. The
limits are module constants: a caller who needs more sets them before
loading, e.g. ``halfslip.limits.MAX_RUN_BYTES = 16 * 2**30``; the command
line reads nothing else.

Each constant says why it has its size. The guiding number is the memory of
an ordinary workstation: a bad or hostile input must fail in well under a
second and a few hundred megabytes, while every scene of the examples,
benchmarks and tests stays orders of magnitude inside.
"""
from __future__ import annotations

MIB = 2**20
GIB = 2**30

# -- files ---------------------------------------------------------------------

MAX_SCENE_BYTES = 4 * MIB
"""Largest scene or sweep file read. PyYAML's pure-Python reader handles about
1 MB/s, and MAX_YAML_NODES nodes of 40 characters each are 4 MB; a real scene
is a few kB."""

MAX_TABLE_BYTES = 64 * MIB
"""Largest CSV file (load table or profile) read: MAX_TABLE_ROWS rows of five
numbers of up to 12 characters each is 64 MB. Reading it needs about five
times its size in memory."""

MAX_TABLE_ROWS = 1_000_000
"""Most lines of a load-table CSV (data, comments and blank lines alike). The
parsed rows take about 200 bytes each in Python (200 MB); a history of this
many steps with fields stored needs a few GB (see MAX_RUN_BYTES)."""

MAX_PROFILE_ROWS = 10_000
"""Most samples of a tabulated profile (CSV lines or inline values). A
symmetric profile's normal problem tabulates the load at every positive
sample, work O(n^2): 10,000 samples take about 10 s once per run; profilometer
traces are usually resampled to a few thousand points across the contact."""

# -- YAML ----------------------------------------------------------------------

MAX_YAML_NODES = 100_000
"""Most YAML nodes (scalars, lists, mappings) a scene or sweep file may
expand to, counting every alias as the full size of its anchor. Stops alias
bombs ("billion laughs": 9 levels of 10 aliases are 10^9 nodes from 0.5 kB).
The largest example scene has under 100 nodes; an inline table of 20,000
rows of 5 loads fits."""

MAX_YAML_DEPTH = 64
"""Deepest nesting of lists and mappings (aliases counted expanded). A scene
nests at most 5 levels (loads[1].cycles.Q.amplitude); the readers recurse
once per level, far below Python's recursion limit of 1000."""

MAX_NUMBER_DIGITS = 400
"""Longest run of digits in one integer literal. A float holds at most
1.8e308 (309 digits); Python refuses to convert integers of more than 4300
digits to text, and converting long ones is quadratic."""

# -- runs and sweeps -----------------------------------------------------------

MAX_RUN_BYTES = 4 * GIB
"""Largest memory estimate of one run (halfslip.scene.run_bytes): the sampled
history, the stored steps with their fields, and the general solver's
working set (GENERAL_BYTES_PER_NODE and GENERAL_BYTES_PER_NODE_PAIR). The
examples need under 50 MB; 10 million stored steps of 201-point fields would
need 48 GB, and 16,384 general-solver nodes about 3.5 GB."""

GENERAL_BYTES_PER_NODE = 4096 + 6144
GENERAL_BYTES_PER_NODE_PAIR = 12
GENERAL_KEPT_BYTES = 64 * 2 ** 20
"""Working memory of the general solver: GENERAL_KEPT_BYTES + GENERAL_BYTES_PER_NODE n +
GENERAL_BYTES_PER_NODE_PAIR n^2 bytes for n nodes. The square term is the
Levinson table of the Toeplitz log kernel (halfslip.solvers._toeplitz: size^2/2
doubles for size = 1.5 n cells, and the same for the half-resolution shadow
lattice of the error estimate: 9 n^2 + 2.25 n^2 bytes). Of the linear term,
6144 bytes a node are what the solver keeps per contact across a periodic
history's cycles (since 0.3.8, general.LOADS_KEPT = 256 cell-load tables of n
doubles and as many end-cell column pairs of 2 n); the lattices' caches of 32
run lengths' generator spectra and T_n^-1 1 (_toeplitz.SLOTS, since 0.4.0) take
2880 bytes a node of the 4096. GENERAL_KEPT_BYTES is a fixed allowance (until
0.4.0 the budget of the end cells' Woodbury columns the solver kept)."""

MAX_SWEEP_CASES = 1_000_000
"""Most cases of a sweep (grid product or explicit list). The result holds
about 10 variables per case plus a status text (some 200 bytes), and each case
runs for a second or more: a million cases is 200 MB of result and days of
computing."""
