"""A probe of every command and option with bad input: zero, negative, NaN, inf, huge, the
wrong type, bad paths and bad files.

Every case must exit with code 2 and print exactly one non-empty line on stderr, starting
with ``error:``, without a traceback, and write nothing: the working folder stays empty, an
``--out``/``--checkpoint`` folder that did not exist is not left behind, one that existed is
unchanged. Each case fails before any work, in about a second or two (the loading of the
command line); the cases that first build a knot's chain take a few seconds more and run with
the slow tests (``make test-all``), as does the long tail of the matrix.

A second part (#40) probes what the machine and the user's files can do to a run: a full disk
(a small tmpfs, mounted for the test where that is permitted), read-only and immutable
databases, curves that meet themselves, of extreme scale, with a byte-order mark or of 10⁵
vertices, two atlases on one folder, Ctrl-C at any moment, threads, mirror names: every case
ends in one clear line and loses nothing.
"""

from __future__ import annotations

import inspect
import re
import shlex
import subprocess
import sys
import typing
from pathlib import Path

import numpy as np
import pytest

_SCRIPT = Path(sys.executable).with_name("stiffknots")
CLI = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "stiffknots.cli"]

# (arguments, regular expression the error line must match, fast): {out} is a folder that does
# not exist yet, {file} an existing file, {ck} a checkpoint folder holding the bad file of the
# case (see CHECKPOINTS), {bad} a folder of bad curve files (see BAD_CURVES), {data} the folder
# of good curves (tests/data/curves/ridgerunner)
CASES = [
    # --- anneal ---------------------------------------------------------------------------
    ("anneal 3_1 --beads abc", r"Invalid value for '--beads'.*not a number", True),
    ("anneal 3_1 --beads 1.5", r"--beads must be an integer in \[8, 20,000\], got 1\.5", False),
    ("anneal 3_1 --beads 0", r"--beads must be an integer", False),
    ("anneal 3_1 --beads -5", r"--beads must be an integer", False),
    ("anneal 3_1 --beads 4", r"--beads must be an integer in \[8, 20,000\]", False),
    ("anneal 3_1 --beads 10", r"the least number of beads that works is 15", False),
    ("anneal 3_1 --beads 200000", r"--beads must be an integer in \[8, 20,000\]", False),
    ("anneal 3_1 --beads 10000000 --out {out}", r"--beads must be an integer in \[8, 20,000\]",
     True),
    ("anneal 3_1 --moves 1e23", r"--moves must be an integer in \[1,000, 1,000,000,000,000\], "
     r"got 100000000000000000000000", True),
    ("anneal 3_1 --moves 0", r"--moves must be an integer", False),
    ("anneal 3_1 --moves -1", r"--moves must be an integer", False),
    ("anneal 3_1 --moves 10", r"--moves must be an integer in \[1,000", False),
    ("anneal 3_1 --moves nan", r"--moves must be an integer", False),
    ("anneal 3_1 --moves lots", r"Invalid value for '--moves'", False),
    ("anneal 3_1 --replicas 0", r"--replicas must be an integer in \[1, 1,000\]", False),
    ("anneal 3_1 --replicas 100000", r"--replicas must be an integer in \[1, 1,000\]", False),
    ("anneal 3_1 --seed -1", r"--seed must be an integer in \[0, ", True),
    ("anneal 3_1 --seed 99999999999999999999999", r"--seed must be an integer", False),
    ("anneal 3_1 --seed x", r"Invalid value for '--seed'", False),
    ("anneal 3_1 --t-start inf", r"--t-start must be a finite number > 0, got inf", False),
    ("anneal 3_1 --t-start nan", r"--t-start must be a finite number > 0, got nan", False),
    ("anneal 3_1 --t-start 0",
     r"--t-start must (be a finite number > 0|lie above the langevin schedule.s final)", False),
    ("anneal 3_1 --t-start -1",
     r"--t-start must (be a finite number > 0|lie above the langevin schedule.s final)", False),
    ("anneal 3_1 --t-end inf", r"--t-end must be a finite number > 0", False),
    ("anneal 3_1 --t-start 1e-7 --t-end 1e-6", r"--t-end must be below t_start", False),
    ("anneal 3_1 --relax-fraction nan", r"--relax-fraction must be in \[0, 1\)", False),
    ("anneal 3_1 --relax-fraction 1", r"--relax-fraction must be in \[0, 1\)", False),
    ("anneal 3_1 --schedule tempering --relax-fraction 0.5",
     r"--relax-fraction applies to the power and geometric schedules", False),
    ("anneal 3_1 --schedule langevin --relax-fraction 0.5",
     r"--relax-fraction applies to the power and geometric schedules \(langevin", False),
    ("anneal 3_1 --schedule langevin --exclusion tube",
     r"--schedule langevin runs the bead rule", False),
    ("anneal 3_1 --schedule langevin --tube-route", r"--schedule langevin runs the bead rule",
     False),
    ("anneal 3_1 --schedule langevin --checkpoint {out}",
     r"--checkpoint applies to the Monte Carlo schedules", False),
    ("anneal 3_1 --schedule langevin --t-start 1e-5",
     r"--t-start must lie above the langevin schedule's final temperature 0\.0001", False),
    ("anneal 3_1 --delta nan", r"--delta must be a finite number in \(0, 0\.5\)", False),
    ("anneal 3_1 --delta inf", r"--delta must be a finite number", False),
    ("anneal 3_1 --delta 0", r"--delta must be a finite number", False),
    ("anneal 3_1 --exclusion tube --w nan", r"--w must be a finite number in \(0, 1\)", False),
    ("anneal 3_1 --exclusion tube --w inf", r"--w must be a finite number", False),
    ("anneal 3_1 --exclusion tube --w 0", r"--w must be a finite number", False),
    ("anneal 3_1 --exclusion tube --w 2", r"--w must be a finite number in \(0, 1\)", False),
    ("anneal 3_1 --w 0.5", r"--w applies to --exclusion tube only", False),
    ("anneal 3_1 --m-max 10000", r"--m-max must be an integer in \[1, 147\]", True),
    ("anneal 3_1 --m-max 0", r"--m-max must be an integer in \[1, 147\]", False),
    ("anneal 3_1 --exclusion soft", r"--exclusion must be one of bead, tube", False),
    ("anneal 3_1 --schedule fast",
     r"--schedule must be one of auto, power, geometric, tempering, langevin", False),
    ("anneal 3_1 --schedule langevin --delta 0.1",
     r"--delta and --m-max set the Monte Carlo moves; the langevin schedule has none", True),
    ("anneal 3_1 --schedule langevin --m-max 10",
     r"--delta and --m-max set the Monte Carlo moves", False),
    ("anneal 3_1 --start box", r"--start must be one of all, braid, cage, eighty", False),
    ("anneal 3_1 --start cage --out {out}", r"two-box rational knots", False),
    ("anneal ''", r"empty knot name", False),
    ("anneal nonsense_knot", r"unknown knot", False),
    ("anneal 4_9", r"unknown knot '4_9'", False),
    ("anneal", r"Missing argument", False),
    ("anneal 3_1 --bogus", r"No such option: --bogus", False),
    # --- anneal: folders --------------------------------------------------------------------
    ("anneal 3_1 --out ''", r"--out must name a folder, got ''", True),
    ("anneal 3_1 --out {file}", r"--out .*: exists and is not a folder", True),
    ("anneal 3_1 --out {file}/sub", r"--out .*: cannot write there \(Not a directory\)", True),
    ("anneal 3_1 --out /proc/x", r"--out /proc/x: cannot write there", True),
    ("anneal 3_1 --out /sys/kernel/x", r"--out /sys/kernel/x: cannot write there", True),
    ("anneal 3_1 --checkpoint ''", r"--checkpoint must name a folder", False),
    ("anneal 3_1 --checkpoint {file}", r"--checkpoint .*: exists and is not a folder", False),
    ("anneal 3_1 --checkpoint {file}/sub", r"--checkpoint .*: cannot write there", False),
    ("anneal 3_1 --checkpoint /proc/x", r"--checkpoint /proc/x: cannot write there", False),
    ("anneal 3_1 --checkpoint /sys/kernel/x", r"--checkpoint /sys/kernel/x: cannot write",
     False),
    ("anneal 3_1 --resume", r"--resume needs --checkpoint DIR", False),
    ("anneal 3_1 --resume --checkpoint {out}", r"--resume: there is no checkpoint folder", True),
    ("anneal 3_1 --resume --checkpoint {ck}/empty --moves 2000 --replicas 2",
     r"corrupt checkpoint .*replica_0\.ckpt\.npz", False),
    ("anneal 3_1 --resume --checkpoint {ck}/truncated --moves 2000 --replicas 2",
     r"corrupt checkpoint .*replica_0\.ckpt\.npz", False),
    ("anneal 3_1 --resume --checkpoint {ck}/junk --moves 2000 --replicas 2",
     r"corrupt checkpoint .*replica_0\.ckpt\.npz", False),
    ("anneal 3_1 --resume --checkpoint {ck}/folder --moves 2000 --replicas 2",
     r"corrupt checkpoint .*replica_0\.ckpt\.npz", False),
    # --- open -------------------------------------------------------------------------------
    ("open 3_1 --excess-length inf", r"--excess-length must be finite numbers, got inf", True),
    ("open 3_1 --excess-length nan", r"--excess-length must be finite numbers, got nan", False),
    ("open 3_1 --excess-length 1e9", r"--excess-length must be an integer in \[8, 10,000\]",
     False),
    ("open 3_1 --excess-length 1000000", r"--excess-length must be an integer in \[8, 10,000\]",
     False),
    ("open 3_1 --excess-length 0", r"--excess-length must be an integer", False),
    ("open 3_1 --excess-length -40", r"--excess-length must be an integer", False),
    ("open 3_1 --excess-length 40.5", r"--excess-length must be an integer", False),
    ("open 3_1 --excess-length abc", r"--excess-length must be numbers separated by commas",
     False),
    ("open 3_1 --excess-length ''", r"--excess-length: give at least one value", True),
    ("open 3_1 --force nan", r"--force must be finite numbers, got nan", True),
    ("open 3_1 --force inf", r"--force must be finite numbers, got inf", False),
    ("open 3_1 --force 0", r"--force must be a finite number > 0", False),
    ("open 3_1 --force -1", r"--force must be a finite number > 0", False),
    ("open 3_1 --excess-length 40 --force 1", r"--force must be in \[1\.97e-07, 0\.308\] C/b²",
     False),
    ("open 3_1 --excess-length 40 --force 1e-300",
     r"--force must be in \[1\.97e-07, 0\.308\] C/b², got 1e-300", False),
    ("open 3_1 --ensemble force", r"--ensemble force needs --force", False),
    ("open 3_1 --ensemble force --force 1e300", r"--force must be a finite number in \[0, 100\]",
     False),
    ("open 3_1 --ensemble force --force 1e-300", r"--force must be ≥ ", False),
    ("open 3_1 --ensemble force --force 1 --beads 5", r"--beads must be an integer", False),
    ("open 3_1 --ensemble force --force 1 --excess-length 40,60", r"one value", False),
    ("open 3_1 --ensemble isotension", r"--ensemble must be one of extension, force", False),
    ("open 3_1 --beads 100", r"--beads applies to --ensemble force only", False),
    ("open 3_1 --moves 1e23", r"--moves must be an integer in \[1,000", False),
    ("open 3_1 --replicas 0", r"--replicas must be an integer", False),
    ("open 3_1 --seed -1", r"--seed must be an integer", False),
    ("open 3_1 --m-max 0", r"--m-max must be an integer", False),
    ("open 3_1 --m-max 10000", r"--m-max must be an integer in \[1, 147\]", False),
    ("open 3_1 --exclusion bead --w 0.1", r"--w applies to --exclusion tube only", False),
    ("open 3_1 --exclusion tube --w nan", r"--w must be a finite number", False),
    ("open 0_1", r"no braid word", False),
    ("open 3_1 --out {file}/sub", r"--out .*: cannot write there", False),
    ("open 3_1 --out /proc/x", r"--out /proc/x: cannot write there", False),
    ("open 3_1 --out /sys/kernel/x", r"--out /sys/kernel/x: cannot write there", False),
    ("open 3_1 --out {file}", r"exists and is not a folder", False),
    ("open 3_1 --out ''", r"--out must name a folder", False),
    # --- tightest ---------------------------------------------------------------------------
    ("tightest 3_1 --max-curvature nan", r"--max-curvature must be a finite number > 0, got nan",
     True),
    ("tightest 3_1 --max-curvature inf", r"--max-curvature must be a finite number > 0, got inf",
     True),
    ("tightest 3_1 --max-curvature 0", r"--max-curvature must be a finite number > 0", False),
    ("tightest 3_1 --max-curvature -1", r"--max-curvature must be a finite number > 0", False),
    ("tightest 3_1 --beads 5", r"--beads must be an integer", False),
    ("tightest 3_1 --beads 10000000", r"--beads must be an integer", False),
    ("tightest 3_1 --moves 1e23", r"--moves must be an integer", False),
    ("tightest 3_1 --moves 0", r"--moves must be an integer", False),
    ("tightest 3_1 --replicas 0", r"--replicas must be an integer", False),
    ("tightest 3_1 --seed -1", r"--seed must be an integer", False),
    ("tightest 3_1 --w nan", r"--w must be a finite number", False),
    ("tightest 3_1 --w inf", r"--w must be a finite number", False),
    ("tightest 3_1 --w 0", r"--w must be a finite number", False),
    ("tightest 3_1 --exclusion bead --w 0.5", r"--w applies to --exclusion tube only", False),
    ("tightest 3_1 --exclusion soft", r"--exclusion must be one of", False),
    ("tightest 3_1 --start box", r"--start must be one of", False),
    ("tightest nonsense", r"unknown knot", False),
    ("tightest 3_1 --out {file}", r"exists and is not a folder", False),
    ("tightest 3_1 --out {file}/sub", r"cannot write there", True),
    ("tightest 3_1 --out /proc/x", r"cannot write there", False),
    ("tightest 3_1 --out /sys/kernel/x", r"cannot write there", False),
    ("tightest 3_1 --out ''", r"--out must name a folder", False),
    # --- elastica, paper, bench, knot, families -----------------------------------------------
    ("elastica --out ''", r"--out must name a folder", False),
    ("elastica --out {file}", r"exists and is not a folder", False),
    ("elastica --out {file}/sub", r"cannot write there", True),
    ("elastica --out /proc/x", r"cannot write there", False),
    ("elastica --out /sys/kernel/x", r"cannot write there", False),
    ("paper --out ''", r"--out must name a folder", False),
    ("paper --out {file}", r"exists and is not a folder", False),
    ("paper --out {file}/sub", r"cannot write there", False),
    ("paper --out /proc/x", r"cannot write there", True),
    ("paper --out /sys/kernel/x", r"cannot write there", False),
    ("paper --budget huge", r"--budget must be one of tiny, small, full", False),
    ("paper --seed -1 --out {out}", r"--seed must be an integer", True),
    ("paper --seed x", r"Invalid value for '--seed'", False),
    ("bench --seconds-budget -1", r"--seconds-budget must be a finite number > 0", True),
    ("bench --seconds-budget 0", r"--seconds-budget must be a finite number > 0", False),
    ("bench --seconds-budget nan", r"--seconds-budget must be a finite number > 0", False),
    ("bench --seconds-budget inf", r"--seconds-budget must be a finite number > 0", False),
    ("bench --seconds-budget x", r"Invalid value for '--seconds-budget'", False),
    ("knot 4_9", r"unknown knot '4_9'", False),
    ("knot ''", r"empty knot name", False),
    ("knot 3_1 --bogus", r"No such option: --bogus", False),
    ("families --max-crossings 0", r"--max-crossings must be between 3 and 13", False),
    ("families --max-crossings 20", r"--max-crossings must be between 3 and 13", False),
    ("families --max-crossings x", r"Invalid value for '--max-crossings'", False),
    ("starts --max-crossings 2", r"--max-crossings must be between 3 and 13, got 2", True),
    ("starts --max-crossings x", r"Invalid value for '--max-crossings'", False),
    ("starts --crossings 14", r"--crossings: whole numbers between 3 and --max-crossings \(12\)",
     True),
    ("starts --crossings 11.5", r"--crossings: whole numbers between 3", False),
    ("starts --families ideal", r"--families 'ideal': choose from braid, cage, eighty", True),
    ("starts --families ''", r"--families '': choose from braid, cage, eighty", False),
    ("starts --beads 10", r"--beads must be between 20 and 100000, got 10", False),
    ("starts --beads x", r"Invalid value for '--beads'", False),
    ("starts --workers 0", r"--workers must be between 1 and 64, got 0", False),
    # --- identify, resample, relax: curve files ({data}: tests/data/curves/ridgerunner) ------
    ("identify {bad}/nothere.xyz", r"nothere\.xyz: no such file", True),
    ("identify ''", r"\.: is a folder; give a chain file", False),
    ("identify {ck}", r"ck: is a folder; give a chain file", False),
    ("identify {bad}/dir.vect", r"dir\.vect: is a folder", False),
    ("identify {file}", r"afile: unknown chain file suffix ''", True),
    ("identify {bad}/empty.xyz", r"empty\.xyz: empty file", False),
    ("identify {bad}/junk.vect", r"junk\.vect, line 1: a VECT file starts with 'VECT'", False),
    ("identify {bad}/junk.json", r"junk\.json: 'format' is None", False),
    ("identify {bad}/junk.npz", r"junk\.npz: not an npz archive", False),
    ("identify {bad}/binary.xyz", r"binary\.xyz: not a text file", False),
    ("identify {bad}/nan.xyz", r"nan\.xyz, line 4: non-finite coordinates", False),
    ("identify {bad}/two.xyz", r"a closed chain needs at least 3 beads, got 2", False),
    ("identify {bad}/same.xyz", r"the same vertex twice in a row", False),
    ("identify {data}/3.1.vect --closed --open --bogus", r"No such option: --bogus", False),
    ("resample {data}/3.1.vect {out}/r.xyz --beads 0", r"--beads must be an integer in "
     r"\[8, 20,000\], got 0", True),
    ("resample {data}/3.1.vect {out}/r.xyz --beads -3", r"--beads must be an integer", False),
    ("resample {data}/3.1.vect {out}/r.xyz --beads 1000000", r"--beads must be an integer",
     False),
    ("resample {data}/3.1.vect {out}/r.xyz --beads abc", r"Invalid value for '--beads'",
     False),
    ("resample {data}/3.1.vect {out}/r.xyz --w-over-L nan",
     r"--w-over-L must be a finite number in \(0, 0.125\], got nan", True),
    ("resample {data}/3.1.vect {out}/r.xyz --w-over-L inf", r"--w-over-L must be a finite number",
     False),
    ("resample {data}/3.1.vect {out}/r.xyz --w-over-L -0.01", r"--w-over-L must be a finite number",
     False),
    ("resample {data}/3.1.vect {out}/r.xyz --w-over-L 1", r"--w-over-L must be a finite number",
     False),
    ("resample {data}/3.1.vect {out}/r.xyz --w-over-L 1e300", r"--w-over-L must be a finite number",
     False),
    ("resample {data}/3.1.vect {out}/r.xyz --w-over-L x", r"Invalid value for '--w-over-L'",
     False),
    ("resample {data}/3.1.vect {out}/r.xyz --open", r"resample needs a closed curve", False),
    ("resample {data}/3.1.vect {out}/r.txt", r"r\.txt: unknown suffix '\.txt'", False),
    ("resample {data}/3.1.vect ''", r"DEST \. is a folder; give the path of a file", False),
    ("resample {data}/3.1.vect {file}/r.xyz", r"DEST .*: cannot write there", True),
    ("resample {data}/3.1.vect /proc/x/r.xyz", r"DEST /proc/x/r\.xyz: cannot write there",
     False),
    ("resample {bad}/nothere.xyz {out}/r.xyz", r"nothere\.xyz: no such file", False),
    ("resample {ck} {out}/r.xyz", r"ck: is a folder; give a chain file", False),
    ("resample {bad}/empty.xyz {out}/r.xyz", r"empty\.xyz: empty file", False),
    ("relax {data}/3.1.vect --beads 0", r"--beads must be an integer in \[8, 20,000\], got 0",
     True),
    ("relax {data}/3.1.vect --beads 1.5", r"--beads must be an integer", False),
    ("relax {data}/3.1.vect --beads 1000000", r"--beads must be an integer", False),
    ("relax {data}/3.1.vect --beads abc", r"Invalid value for '--beads'", False),
    ("relax {data}/3.1.vect --beads 10", r"thinner than the model .*use --beads ≥ 12", False),
    ("relax {data}/3.1.vect --exclusion soft", r"--exclusion must be one of bead, tube", True),
    ("relax {data}/3.1.vect --exclusion tube",
     r"--w-over-L must be a number in \(0, 1/8\] with the tube model .*it was not given",
     False),
    ("relax {data}/3.1.vect --w-over-L nan", r"--w-over-L must be a finite number in "
     r"\(0, 0\.125\], got nan", True),
    ("relax {data}/3.1.vect --w-over-L inf", r"--w-over-L must be a finite number", False),
    ("relax {data}/3.1.vect --w-over-L 0", r"--w-over-L must be a finite number", False),
    ("relax {data}/3.1.vect --w-over-L -1", r"--w-over-L must be a finite number", False),
    ("relax {data}/3.1.vect --w-over-L 0.1", r"--w-over-L must be below 1/N = 0\.00667",
     False),
    ("relax {data}/3.1.vect --w-over-L x", r"Invalid value for '--w-over-L'", False),
    ("relax {data}/3.1.vect --knot ''", r"--knot must be a knot name such as 3_1", True),
    ("relax {data}/3.1.vect --knot nonsense", r"unknown knot 'nonsense'", False),
    ("relax {data}/3.1.vect --knot 3_1#nonsense", r"unknown knot 'nonsense'", False),
    ("relax {data}/3.1.vect --knot 4_1", r"the curve is 3_1, not 4_1", False),
    ("relax {data}/3.1.vect --moves 0", r"--moves must be an integer in \[1,000", True),
    ("relax {data}/3.1.vect --moves -5", r"--moves must be an integer", False),
    ("relax {data}/3.1.vect --moves 1e23", r"--moves must be an integer in \[1,000, "
     r"1,000,000,000,000\], got 100000000000000000000000", False),
    ("relax {data}/3.1.vect --moves nan", r"--moves must be an integer", False),
    ("relax {data}/3.1.vect --moves lots", r"Invalid value for '--moves'", False),
    ("relax {data}/3.1.vect --replicas 0", r"--replicas must be an integer in \[1, 1,000\]",
     True),
    ("relax {data}/3.1.vect --replicas 100000", r"--replicas must be an integer", False),
    ("relax {data}/3.1.vect --replicas x", r"Invalid value for '--replicas'", False),
    ("relax {data}/3.1.vect --seed -1", r"--seed must be an integer in \[0, ", True),
    ("relax {data}/3.1.vect --seed 99999999999999999999999", r"--seed must be an integer",
     False),
    ("relax {data}/3.1.vect --seed x", r"Invalid value for '--seed'", False),
    ("relax {data}/3.1.vect --open", r"relax takes a closed curve", False),
    ("relax {data}/3.1.vect --out ''", r"--out must name a folder, got ''", False),
    ("relax {data}/3.1.vect --out {file}", r"--out .*: exists and is not a folder", True),
    ("relax {data}/3.1.vect --out {file}/sub", r"--out .*: cannot write there", False),
    ("relax {data}/3.1.vect --out /proc/x", r"--out /proc/x: cannot write there", False),
    ("relax {data}/3.1.vect --out {out} --seed -1", r"--seed must be an integer", False),
    ("relax {bad}/nothere.vect --out {out}", r"nothere\.vect: no such file", False),
    ("relax {bad}/junk.vect", r"a VECT file starts with 'VECT'", False),
    # --- anneal: --rounds, --from -------------------------------------------------------------
    ("anneal 3_1 --rounds 0", r"--rounds must be an integer in \[1, 100\], got 0", True),
    ("anneal 3_1 --rounds -1", r"--rounds must be an integer in \[1, 100\]", False),
    ("anneal 3_1 --rounds 1000", r"--rounds must be an integer in \[1, 100\]", False),
    ("anneal 3_1 --rounds 1.5", r"Invalid value for '--rounds'", False),
    ("anneal 3_1 --rounds x", r"Invalid value for '--rounds'", False),
    ("anneal 3_1 --from ''", r"--from must name a curve file, got ''", True),
    ("anneal 3_1 --coarse 2", r"--coarse must be an integer in \[8, 20,000\], got 2", True),
    ("anneal 3_1 --coarse 150", r"--coarse must be fewer beads than --beads \(150\)", True),
    ("anneal 3_1 --beads 300 --coarse 150 --from {file}",
     r"--coarse and --from both give the starting chain", True),
    ("anneal 3_1 --beads 300 --coarse 150 --w-over-L 0.002",
     r"--coarse keeps the tube's diameter w in bond units", True),
    ("anneal 3_1 --from {bad}/nothere.xyz", r"--from .*nothere\.xyz: no such file", True),
    ("anneal 3_1 --from {bad}/nothere.xyz --out {out}", r"--from .*: no such file", False),
    ("anneal 3_1 --from {file}", r"--from .*afile: unknown chain file suffix ''", False),
    ("anneal 3_1 --from /proc/x", r"--from /proc/x: unknown chain file suffix", False),
    ("anneal 3_1 --from {ck}", r"--from .*ck: is a folder; give a chain file", False),
    ("anneal 3_1 --from {bad}/dir.vect", r"--from .*dir\.vect: is a folder", False),
    ("anneal 3_1 --from {bad}/empty.xyz", r"--from .*empty\.xyz: empty file", False),
    ("anneal 3_1 --from {bad}/junk.vect", r"--from .*: a VECT file starts with 'VECT'", False),
    ("anneal 3_1 --from {bad}/junk.npz", r"--from .*: not an npz archive", False),
    ("anneal 3_1 --from {bad}/binary.xyz", r"--from .*: not a text file", False),
    ("anneal 3_1 --from {bad}/nan.xyz", r"--from .*: non-finite coordinates", False),
    ("anneal 3_1 --from {bad}/two.xyz", r"--from .*: a closed chain needs at least 3 beads",
     False),
    ("anneal 3_1 --from {data}/4.1.vect", r"the curve is 4_1, not 3_1", False),
    # --- audit --------------------------------------------------------------------------------
    ("audit", r"no results database at results/stiffknots\.db", True),
    ("audit --db ''", r"--db must name a results database file, got ''", False),
    ("audit --db {out}", r"no results database at .*out", False),
    ("audit --db {file}", r"--db .*afile: .* is not an SQLite database", True),
    ("audit --db {bad}/empty.xyz", r"--db .*empty\.xyz: .* is empty: no results database",
     False),
    ("audit --sample 0", r"--sample must be an integer in \[1, 100,000\], got 0", True),
    ("audit --sample x", r"Invalid value for '--sample'", False),
    ("audit --seed -1", r"--seed must be an integer in \[0, ", False),
    ("audit --depth 0", r"--depth must be a number of replica budgets in \[0\.1, 1000\]",
     True),
    ("audit --depth x", r"Invalid value for '--depth'", False),
    ("audit --replicas 0", r"--replicas must be an integer in \[1, 1,000\], got 0", False),
    ("audit --models foo", r"--models must be tube and/or bead", True),
    ("audit --models ''", r"--models must be tube and/or bead", False),
    ("audit --max-crossings 2", r"--max-crossings must be an integer in \[3, 13\], got 2",
     False),
    ("audit --max-crossings x", r"Invalid value for '--max-crossings'", False),
    ("audit --scheduler nonsense", r"--scheduler must be a scheduler address", False),
    ("audit --workers 0", r"--workers must be an integer in \[1, 1,024\], got 0", False),
    ("audit --workers 2 --scheduler tcp://h:1", r"--workers is for the local cluster", False),
    ("audit --knots ,", r"--knots must be knot names separated by commas", True),
    ("audit --knots 3_1,7_99", r"unknown knot '7_99'", False),
    # --- atlas --------------------------------------------------------------------------------
    ("atlas", r"give --max-crossings K .* or --knots", False),
    ("atlas --max-crossings 0", r"--max-crossings must be an integer in \[3, 13\], got 0", True),
    ("atlas --max-crossings 2", r"--max-crossings must be an integer in \[3, 13\]", False),
    ("atlas --max-crossings 14", r"--max-crossings must be an integer in \[3, 13\]", False),
    ("atlas --max-crossings -1", r"--max-crossings must be an integer in \[3, 13\]", False),
    ("atlas --max-crossings x", r"Invalid value for '--max-crossings'", False),
    ("atlas --knots ''", r"--knots must be knot names separated by commas", True),
    ("atlas --knots ,,", r"--knots must be knot names separated by commas", False),
    ("atlas --knots nonsense", r"unknown knot 'nonsense'", False),
    ("atlas --knots 0_1", r"the unknot has no knotted ground state", False),
    ("atlas --knots 5_1 --max-crossings 3", r"5_1 has 5 crossings, more than", False),
    ("atlas --knots 3_1 --models ''", r"--models must be bead and/or tube", False),
    ("atlas --knots 3_1 --models soft", r"--models must be bead and/or tube, separated by "
     r"commas, got 'soft'", True),
    ("atlas --knots 3_1 --models bead,soft", r"--models must be bead and/or tube", False),
    ("atlas --knots 3_1 --budget huge", r"--budget must be one of tiny, small, default, full",
     True),
    ("atlas --knots 3_1 --budget ''", r"--budget must be one of", False),
    ("atlas --knots 3_1 --bead-search dynamics",
     r"--bead-search must be one of annealing, langevin, got 'dynamics'", True),
    ("atlas --knots 3_1 --models tube --bead-search langevin",
     r"--bead-search sets the bead model's search: add bead to --models", True),
    ("atlas --knots 3_1 --models tube --coarse 150",
     r"--coarse must be an integer in \[3, 149\], got 150", True),
    ("atlas --knots 3_1 --models tube --coarse 2.5", r"--coarse must be an integer", False),
    ("atlas --knots 3_1 --models bead --coarse 100",
     r"--coarse sets the tube model's replicas: add tube to --models", True),
    ("atlas --knots 3_1 --bead-steps 10",
     r"--bead-steps must be an integer in \[1,000, 1,000,000,000,000\], got 10", True),
    ("atlas --knots 3_1 --bead-steps 2.5", r"--bead-steps must be an integer", False),
    ("atlas --knots 3_1 --models bead --thin",
     r"--thin follows the tube model's states to w = 0: add tube to --models", True),
    ("atlas --knots 3_1 --thin --thin-budget huge",
     r"--thin-budget must be one of small, default, got 'huge'", True),
    ("atlas --knots 3_1 --thin --thin-states 0", r"--thin-states must be an integer", True),
    ("atlas --knots 3_1 --thin --thin-states 2.5", r"--thin-states must be an integer", False),
    ("atlas --knots 3_1 --thin-states 2", r"--thin-budget and --thin-states set the thin "
     r"stage: add --thin", True),
    ("atlas --knots 3_1 --thin-budget default", r"add --thin", False),
    ("atlas --knots 3_1 --thin --stored", r"--thin runs the thin stage and --stored runs "
     r"nothing", True),
    ("atlas --knots 3_1 --budget tiny --bead-steps 2e6",
     r"--bead-steps must be given with a Langevin bead search only \(bead search langevin, "
     r"the default and full budgets'\), not with annealing", True),
    ("atlas --knots 3_1 --models tube --bead-steps 2e6",
     r"--bead-steps sets the bead model's dynamics: add bead to --models", True),
    ("atlas --knots 3_1 --out ''", r"--out must name a folder, got ''", False),
    ("atlas --knots 3_1 --out {file}", r"--out .*: exists and is not a folder", False),
    ("atlas --knots 3_1 --out {file}/sub", r"--out .*: cannot write there", False),
    ("atlas --knots 3_1 --out /proc/x", r"--out /proc/x: cannot write there", False),
    ("atlas --knots 3_1 --db {out}/x.db --out {file}", r"--out .*: exists and is not a folder",
     False),
    ("atlas --knots 3_1 --db ''", r"--db must name a file, got ''", False),
    ("atlas --knots 3_1 --db {ck}", r"--db .*ck is a folder; give the path of a file", False),
    ("atlas --knots 3_1 --db {file}/x.db", r"--db .*: cannot write there", False),
    ("atlas --knots 3_1 --db /proc/x.db", r"--db /proc/x\.db: cannot write there", False),
    ("atlas --knots 3_1 --db {file}", r"afile is not an SQLite database", False),
    ("atlas --knots 3_1 --scheduler ''", r"--scheduler must be a scheduler address", False),
    ("atlas --knots 3_1 --scheduler nonsense", r"--scheduler must be a scheduler address such "
     r"as tcp://host:8786 or a scheduler file, got 'nonsense'", True),
    ("atlas --knots 3_1 --scheduler {file}", r"is a file but not a Dask scheduler file", False),
    ("atlas --crossings 14", r"--crossings must be an integer in \[3, 13\], got 14", True),
    ("atlas --crossings 11,x", r"--crossings must be numbers separated by commas", False),
    ("atlas --crossings 11.5", r"--crossings must be whole numbers, got '11\.5'", False),
    ("atlas --crossings 11 --max-crossings 10", r"--crossings must be an integer in \[3, 10\]",
     False),
    ("atlas --crossings 11 --sample 0", r"--sample must be an integer in \[1, 100,000\], got 0",
     True),
    ("atlas --crossings 11 --sample x", r"Invalid value for '--sample'", False),
    ("atlas --knots 3_1 --scheduler tcp://", r"--scheduler must be a scheduler address", False),
    ("atlas --knots 3_1 --scheduler tcp://localhost:8786 --workers 2",
     r"--workers is for the local cluster", False),
    ("atlas --knots 3_1 --workers 0", r"--workers must be an integer in \[1, 1,024\], got 0",
     True),
    ("atlas --knots 3_1 --workers -1", r"--workers must be an integer", False),
    ("atlas --knots 3_1 --workers 100000", r"--workers must be an integer", False),
    ("atlas --knots 3_1 --workers x", r"Invalid value for '--workers'", False),
    ("atlas --knots 3_1 --w nan", r"--w must be a finite number in \(0, 1\), got nan", True),
    ("atlas --knots 3_1 --w inf", r"--w must be a finite number in \(0, 1\)", False),
    ("atlas --knots 3_1 --w 0", r"--w must be a finite number in \(0, 1\)", False),
    ("atlas --knots 3_1 --w -1", r"--w must be a finite number in \(0, 1\)", False),
    ("atlas --knots 3_1 --w 1e300", r"--w must be a finite number in \(0, 1\)", False),
    ("atlas --knots 3_1 --w x", r"Invalid value for '--w'", False),
    ("atlas --knots 3_1 --models bead --w 0.5", r"--w is the tube diameter: add tube", False),
    ("atlas --knots 3_1 --replicas 0", r"--replicas must be an integer in \[1, 1,000\]", True),
    ("atlas --knots 3_1 --replicas -1", r"--replicas must be an integer", False),
    ("atlas --knots 3_1 --replicas 1.5", r"--replicas must be an integer", False),
    ("atlas --knots 3_1 --replicas 100000", r"--replicas must be an integer", False),
    ("atlas --knots 3_1 --replicas x", r"Invalid value for '--replicas'", False),
    ("atlas --knots 3_1 --moves 0", r"--moves must be an integer in \[1,000", False),
    ("atlas --knots 3_1 --moves 10", r"--moves must be an integer in \[1,000", False),
    ("atlas --knots 3_1 --moves -1", r"--moves must be an integer", False),
    ("atlas --knots 3_1 --moves 1e23", r"--moves must be an integer in \[1,000, "
     r"1,000,000,000,000\], got 100000000000000000000000", True),
    ("atlas --knots 3_1 --moves nan", r"--moves must be an integer", False),
    ("atlas --knots 3_1 --moves lots", r"Invalid value for '--moves'", False),
    ("atlas --knots 3_1 --max-replicas 0", r"--max-replicas must be an integer in \[2, 1,000\]",
     True),
    ("atlas --knots 3_1 --max-replicas 1", r"--max-replicas must be an integer in \[2, 1,000\]",
     False),
    ("atlas --knots 3_1 --max-replicas 100000", r"--max-replicas must be an integer", False),
    ("atlas --knots 3_1 --max-replicas nan", r"--max-replicas must be an integer", False),
    ("atlas --knots 3_1 --seed -1", r"--seed must be an integer in \[0, ", True),
    ("atlas --knots 3_1 --seed 99999999999999999999999", r"--seed must be an integer", False),
    ("atlas --knots 3_1 --seed x", r"Invalid value for '--seed'", False),
    ("bogus-command", r"No such command 'bogus-command'", True),
    # --- the thin limit: --w-over-L of anneal and open, thin-limit ------------------------
    ("anneal 3_1 --w-over-L 0", r"--w-over-L must be a finite number in \(0, 0\.125\], got 0\.0",
     True),
    ("anneal 3_1 --w-over-L nan", r"--w-over-L must be a finite number in \(0, 0\.125\]", True),
    ("anneal 3_1 --w-over-L 0.5", r"--w-over-L must be a finite number in \(0, 0\.125\]", False),
    ("anneal 3_1 --w-over-L -1", r"--w-over-L must be a finite number", False),
    ("anneal 3_1 --w-over-L 0.001 --w 0.1", r"--w and --w-over-L both set the tube's diameter",
     False),
    ("open 3_1 --w-over-L 0", r"--w-over-L must be a finite number in \(0, 0\.125\]", True),
    ("open 3_1 --w-over-L inf", r"--w-over-L must be a finite number in \(0, 0\.125\]", False),
    ("open 3_1 --w-over-L 0.001 --w 0.1", r"--w and --w-over-L both set the tube's diameter",
     False),
    ("thin-limit 3_1 --budget huge", r"--budget must be one of small, default, got 'huge'", True),
    ("thin-limit 3_1 --seed -1", r"--seed must be an integer in \[0, ", True),
    ("thin-limit 3_1 --seed abc", r"Invalid value for '--seed'", False),
    ("thin-limit 3_1 --states 0", r"--states must be an integer in \[1, 1,000\], got 0", False),
    ("thin-limit 3_1 --states x", r"Invalid value for '--states'", False),
    # --- census -------------------------------------------------------------------------------
    ("census --db {out}", r"no results database at .*out", True),
    ("census --db {file} --model rope", r"--model must be one of", False),
    ("census --window -1", r"--window must be in \[0, 10\), got -1", False),
    ("census --rel-tol 2", r"--rel-tol must be in \[0, 1\), got 2", False),
    ("census --max-distance nan", r"--max-distance must be in \[0, 1\), got nan", False),
    ("thin-limit 3_1 --out /proc/x", r"--out /proc/x: cannot write there", False),
    ("thin-limit 3_1 --out ''", r"--out must name a folder, got ''", False),
    ("thin-limit nope", r"unknown knot 'nope'", False),
]

CHECKPOINTS = {"empty": b"", "junk": b"junk, not a checkpoint\n",
               "truncated": b"PK\x03\x04" + bytes(200)}

# curve files that cannot be read (identify, resample, relax, anneal --from)
BAD_CURVES = {"empty.xyz": b"", "junk.vect": b"junk\n", "junk.json": b'{"a": 1}\n',
              "junk.npz": b"junk, not an archive\n", "binary.xyz": bytes(range(256)),
              "nan.xyz": b"3\na NaN vertex\nC 0 0 0\nC nan 0 0\nC 1 1 0\n",
              "two.xyz": b"2\ntwo vertices\nC 0 0 0\nC 1 0 0\n",
              "same.xyz": b"4\none vertex\n" + b"C 0 0 0\n" * 4}

DATA = Path(__file__).resolve().parents[1] / "data" / "curves" / "ridgerunner"


def _fixtures(root: Path) -> dict[str, str]:
    """An existing file, bad checkpoints (one folder per kind), bad curve files, and a folder
    that does not exist yet; returns the placeholders."""
    fx = root / "fixtures"
    fx.mkdir()
    (fx / "afile").write_text("not a folder\n")
    for kind, data in CHECKPOINTS.items():
        (fx / "ck" / kind).mkdir(parents=True)
        (fx / "ck" / kind / "replica_0.ckpt.npz").write_bytes(data)
    (fx / "ck" / "folder" / "replica_0.ckpt.npz").mkdir(parents=True)
    (fx / "bad" / "dir.vect").mkdir(parents=True)  # a folder named like a curve file
    for name, data in BAD_CURVES.items():
        (fx / "bad" / name).write_bytes(data)
    return {"{file}": str(fx / "afile"), "{ck}": str(fx / "ck"), "{bad}": str(fx / "bad"),
            "{data}": str(DATA), "{out}": str(root / "new" / "out")}


def _snapshot(folder: Path) -> dict[str, bytes | None]:
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else None)
            for p in sorted(folder.rglob("*"))}


def _params():
    for args, pattern, fast in CASES:
        yield pytest.param(args, pattern, id=args[:70],
                           marks=() if fast else pytest.mark.slow)


@pytest.mark.parametrize(("args", "pattern"), list(_params()))
def test_bad_input_is_one_line_exit_2_nothing_written(tmp_path, args, pattern):
    places = _fixtures(tmp_path)
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    before = _snapshot(tmp_path / "fixtures")
    argv = shlex.split(args)
    for key, value in places.items():
        argv = [a.replace(key, value) for a in argv]
    p = subprocess.run([*CLI, *argv], cwd=cwd, capture_output=True, text=True, timeout=300)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2, (p.returncode, p.stderr[-2000:])
    assert "Traceback" not in p.stderr
    assert len(lines) == 1, p.stderr
    assert lines[0].startswith("error:"), lines[0]
    assert re.search(pattern, lines[0]), lines[0]
    assert p.stdout == ""
    # nothing written: the working folder is empty, a new --out is not left behind, the
    # existing files and folders are untouched
    assert list(cwd.iterdir()) == []
    assert not (tmp_path / "new").exists()
    assert _snapshot(tmp_path / "fixtures") == before


def test_every_option_of_every_command_is_probed():
    """Each option that takes a value appears in at least one probe case of its command (a new
    option needs its bad values here too)."""
    from stiffknots.cli import app

    missing = []
    for cmd in app.registered_commands:
        name = cmd.name or cmd.callback.__name__
        hints = typing.get_type_hints(cmd.callback, include_extras=True)
        for pname in inspect.signature(cmd.callback).parameters:
            ann = hints[pname]
            opts = [m for m in getattr(ann, "__metadata__", ()) if type(m).__name__ == "OptionInfo"]
            base = typing.get_args(ann)[0] if opts else None
            if not opts or set(typing.get_args(base) or (base,)) <= {bool, type(None)}:
                # an argument (probed through the knot names) or a flag: bool, or bool | None
                # (a pair such as --closed/--open, unset by default)
                continue
            o = opts[0]  # typer.Option("--out", ...) keeps the name as its default
            decls = [d for d in (*(o.param_decls or ()), o.default)
                     if isinstance(d, str) and d.startswith("--")]
            flag = decls[0] if decls else "--" + pname.strip("_").replace("_", "-")
            if not any(a.split()[0] == name and flag in a.split() for a, _, _ in CASES):
                missing.append(f"{name} {flag}")
    assert not missing, f"options without a probe case: {missing}"


def test_resume_check_happens_before_any_work(tmp_path, monkeypatch):
    """validate.checkpoints: solve reads every checkpoint before the workers start."""
    from stiffknots.errors import CheckpointError
    from stiffknots.problems import base
    from stiffknots.problems import validate as V
    from stiffknots.problems.closed import ClosedAnneal

    def no_work(*args, **kwargs):
        raise AssertionError("the replicas started")

    monkeypatch.setattr(base, "run_jobs", no_work)

    ck = tmp_path / "ck"
    ck.mkdir()
    problem = ClosedAnneal("3_1", moves=2000, replicas=2, checkpoint_dir=ck, resume=True)
    V.checkpoints(problem.jobs())  # no checkpoint yet: nothing to check, the run starts afresh
    for data in CHECKPOINTS.values():
        (ck / "replica_1.ckpt.npz").write_bytes(data)
        with pytest.raises(CheckpointError, match=r"corrupt checkpoint .*replica_1\.ckpt\.npz"):
            base.solve(problem)
    (ck / "replica_1.ckpt.npz").unlink()
    # a checkpoint of another run: refused before any work too
    from stiffknots.engine.checkpoints import run_meta, save_checkpoint

    job = problem.jobs()[1]
    meta = run_meta("anneal", job.settings, job.seed + 1, job.replica, job.coords)
    save_checkpoint(ck / "replica_1.ckpt.npz", {"pos": np.zeros((3, 3))}, meta)
    with pytest.raises(CheckpointError, match="different run .*seed differs"):
        base.solve(problem)


# ==============================================================================================
# #40: full disks, read-only stores, singular/extreme/BOM curves, huge files, threads,
# concurrent --out, mirror names. Each case ends in one clear line (an ``error:`` line where it
# fails) and loses nothing.
# ==============================================================================================


def _cli(*args, cwd=None, timeout=300, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, **kw)


def _one_error_line(p: subprocess.CompletedProcess, pattern: str, codes=(1, 2)) -> str:
    """The command failed with one ``error:`` line on stderr matching ``pattern``."""
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode in codes, (p.returncode, p.stderr[-3000:])
    assert "Traceback" not in p.stderr, p.stderr[-3000:]
    assert len(lines) == 1, p.stderr[-3000:]
    assert lines[0].startswith("error:"), lines[0]
    assert re.search(pattern, lines[0]), lines[0]
    return lines[0]


# --- mirror names (row 13) --------------------------------------------------------------------


@pytest.mark.parametrize("name", ["3_1*", "m3_1", "3_1m"])
def test_mirror_names_are_read_as_the_knot_and_said(name):
    p = _cli("knot", name)
    assert p.returncode == 0, p.stderr
    text = " ".join(p.stdout.split())
    assert "knot 3_1" in text
    assert "mirror image of 3_1" in text and "do not depend on the mirror" in text


# --- singular, extreme and BOM curves (rows 6, 7, 8, 12) --------------------------------------


def test_a_byte_order_mark_keeps_every_vertex(tmp_path):
    x = np.loadtxt(DATA / "3.1.vect", skiprows=5, max_rows=46)  # the trefoil of ridgerunner
    (tmp_path / "plain.txt").write_text("\n".join(" ".join(map(str, p)) for p in x) + "\n")
    (tmp_path / "bom.txt").write_bytes(b"\xef\xbb\xbf" + (tmp_path / "plain.txt").read_bytes())
    import json

    beads = [json.loads(_cli("identify", tmp_path / f, "--json").stdout)["beads"]
             for f in ("plain.txt", "bom.txt")]
    assert beads == [46, 46]


def _ridgerunner_trefoil() -> np.ndarray:
    return np.loadtxt(DATA / "3.1.vect", skiprows=5, max_rows=46)


def _write_curve(path: Path, x: np.ndarray) -> Path:
    path.write_text("\n".join(" ".join(repr(float(v)) for v in p) for p in x) + "\n")
    return path


@pytest.mark.parametrize(("command", "case"), [("identify", "flattened"), ("identify", "bowtie"),
                                               ("resample", "bowtie"), ("relax", "flattened")])
def test_a_singular_curve_is_refused_naming_the_curve(tmp_path, case, command):
    """Rows 6 and 12: a polygon whose edges cross has no knot type: identify named it 0_1,
    resample and relax blamed --beads."""
    x = _ridgerunner_trefoil()
    x[:, 2] = 0.0
    if case == "bowtie":
        x = np.array([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0.0]])
    f = _write_curve(tmp_path / f"{case}.txt", x)
    extra = [tmp_path / "out.xyz"] if command == "resample" else []
    p = _cli(command, f, *extra, cwd=tmp_path)
    line = _one_error_line(p, r"the curve meets itself \(its edges \d+ and \d+.*no knot type",
                           codes=(2,))
    assert "--beads" not in line
    assert sorted(q.name for q in tmp_path.iterdir()) == [f.name]


def test_a_trefoil_at_1e300_is_a_trefoil(tmp_path):
    """Row 7: scaled by 1e300 it was named 0_1 (an overflow in the crossing tests)."""
    import json

    f = _write_curve(tmp_path / "big.txt", _ridgerunner_trefoil() * 1e300)
    p = _cli("identify", f, "--json")
    assert p.returncode == 0 and p.stderr == "", p.stderr
    d = json.loads(p.stdout)
    assert d["knot"] == "3_1"
    assert d["input_epsilon"] == pytest.approx(115.6535, abs=1e-4)
    assert 1e300 < d["bond_length_range"][0] < d["bond_length_range"][1] < 1e301


# --- huge curve files (row 9) -----------------------------------------------------------------


def test_a_curve_beyond_the_limit_is_refused_at_once(tmp_path):
    """Row 9: 10⁵–10⁶ vertices ran for minutes to hours in topoly, 800 MB, deaf to SIGTERM."""
    from stiffknots.cli.curves import MAX_VERTICES

    t = np.linspace(0, 2 * np.pi, MAX_VERTICES + 1, endpoint=False)
    f = _write_curve(tmp_path / "huge.txt", np.column_stack(
        [(2 + np.cos(3 * t)) * np.cos(2 * t), (2 + np.cos(3 * t)) * np.sin(2 * t),
         np.sin(3 * t)]))
    for args in (["identify", f], ["resample", f, tmp_path / "r.xyz"]):
        p = _cli(*args, cwd=tmp_path, timeout=60)
        _one_error_line(p, r"huge\.txt: 20,001 vertices; .* at most 20,000", codes=(2,))
    assert sorted(q.name for q in tmp_path.iterdir()) == ["huge.txt"]


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_long_identification_says_so_and_stops_at_sigterm(tmp_path):
    """Row 9: a polygon of thousands of vertices says that the invariants take time, and
    ``kill PID`` stops it within seconds (it waited for topoly's compiled code), the forked
    child that computes included."""
    import signal
    import time

    t = np.linspace(0, 2 * np.pi, 12_000, endpoint=False)
    f = _write_curve(tmp_path / "long.txt", np.column_stack(
        [(2 + np.cos(3 * t)) * np.cos(2 * t), (2 + np.cos(3 * t)) * np.sin(2 * t),
         np.sin(3 * t)]))
    p = subprocess.Popen([*CLI, "identify", str(f)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    first = p.stderr.readline()  # waits for the line (before the fix: the run's end)
    assert "12,000 vertices: computing the knot invariants" in first, first
    time.sleep(2)
    assert p.poll() is None
    children = subprocess.run(["pgrep", "-P", str(p.pid)], capture_output=True,
                              text=True).stdout.split()
    t0 = time.monotonic()
    p.send_signal(signal.SIGTERM)
    rc = p.wait(timeout=60)
    assert time.monotonic() - t0 < 5
    rest = p.stderr.read()
    assert rc == 143, rest
    assert "Traceback" not in rest and rest.strip() == "interrupted", rest
    for pid in children:  # the child computing the invariants is gone
        assert not Path(f"/proc/{pid}").exists() or "zombie" in Path(
            f"/proc/{pid}/status").read_text()


# --- read-only stores (rows 2, 3, 14) ---------------------------------------------------------


def _results_db(path: Path) -> Path:
    """A results database with one 5_2 replica (written through the API)."""
    from stiffknots.store import Store

    row = {"knot": "5_2", "exclusion": "bead", "beads": 150, "thickness": 2 ** -0.5,
           "seed": 0, "replica": 0, "settings": {"problem": "anneal", "moves": 1000},
           "epsilon": 128.4, "min_segment_distance": 0.72, "wall_seconds": 1.0,
           "shape": "4C", "start": "cage"}
    with Store(path) as s:
        s.put(row, np.random.default_rng(0).normal(size=(150, 3)))
    return path


def test_a_query_reads_a_database_on_a_read_only_mount(small_fs, tmp_path):
    """Row 3: 'is not a usable SQLite database' for a good file on a read-only mount."""
    fs = small_fs("4m")
    db = _results_db(fs / "r.db")
    small_fs.readonly(fs)
    p = _cli("db", "--db", db, "states", "5_2", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "5_2" in p.stdout and "128.4" in p.stdout


def test_a_query_of_an_empty_file_writes_nothing_into_it(tmp_path):
    """Row 14: the query wrote the schema into a 0-byte --db."""
    (tmp_path / "empty.db").write_bytes(b"")
    for args in (["states", "3_1"], ["grounds"]):
        p = _cli("db", "--db", tmp_path / "empty.db", *args, cwd=tmp_path)
        _one_error_line(p, r"empty\.db is empty: no results database yet", codes=(2,))
    assert [(q.name, q.stat().st_size) for q in tmp_path.iterdir()] == [("empty.db", 0)]


def test_atlas_refuses_a_database_it_cannot_write_before_any_work(immutable, tmp_path):
    """Row 2: the pre-flight looked at the folder only (a read-only mount was refused, an
    immutable file in a writable folder not); the first replica computed was lost with a
    traceback ('attempt to write a readonly database')."""
    db = immutable(_results_db(tmp_path / "r.db"))
    before = db.read_bytes()
    p = _cli("atlas", "--knots", "3_1", "--budget", "tiny", "--db", db, "--out",
             tmp_path / "atlas", cwd=tmp_path)
    _one_error_line(p, r"--db .*r\.db: cannot write it \(Operation not permitted\)",
                    codes=(2,))
    assert db.read_bytes() == before
    assert not (tmp_path / "atlas").exists()


# --- a full disk, Ctrl-C and --overwrite (rows 1, 4) ----------------------------------------


def _ends_in_one_error_line(p: subprocess.CompletedProcess, pattern: str, codes=(1, 2)) -> str:
    """The command's last line on stderr is its one ``error:`` line (progress lines of the
    work done before may precede it), without a traceback."""
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode in codes, (p.returncode, p.stderr[-3000:])
    assert "Traceback" not in p.stderr and "Error:" not in p.stderr, p.stderr[-3000:]
    assert [ln for ln in lines if ln.startswith("error:")] == lines[-1:], p.stderr[-3000:]
    assert re.search(pattern, lines[-1]), lines[-1]
    return lines[-1]


def _earlier_results(out: Path) -> dict:
    """A folder holding an earlier run's results (as anneal writes them)."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "result.json").write_text('{"knot": "3_1", "epsilon": 80.1}\n')
    (out / "best.xyz").write_text("1 0 0 0\n2 1 0 0\n3 0 1 0\n1 0 0 0\n")
    (out / "manifest.json").write_text('{"command": "anneal", "files": ["best.xyz", '
                                       '"result.json"]}\n')
    (out / "mine.txt").write_text("a file of the user's\n")
    return _snapshot(out)


QUICK_ANNEAL = ["anneal", "3_1", "--beads", "40", "--moves", "2000", "--replicas", "1",
                "--rounds", "1", "--schedule", "geometric", "--no-polish"]


def test_overwrite_on_a_full_disk_keeps_the_earlier_results(small_fs, tmp_path):
    """Rows 1 and 4: --overwrite deleted the earlier results first; the new ones then did not
    fit: a traceback and an empty folder."""
    from helpers import fill_up

    fs = small_fs("1m")
    before = _earlier_results(fs / "out")
    fill_up(fs, leave=4096)
    p = _cli(*QUICK_ANNEAL, "--out", fs / "out", "--overwrite", cwd=tmp_path)
    _ends_in_one_error_line(p, r"error: cannot write .*out.*: no space left on device",
                            codes=(1,))
    assert _snapshot(fs / "out") == before  # nothing lost, nothing half-written


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_during_an_overwrite_keeps_the_earlier_results(tmp_path):
    """Row 1: Ctrl-C at 6 s of `anneal 4_1 --out DIR --overwrite` left DIR empty."""
    import signal
    import time

    before = _earlier_results(tmp_path / "out")
    # SIGINT at its default: a process started by a non-interactive shell or a test runner's
    # worker may inherit it ignored (tests/cli/test_signals.py)
    p = subprocess.Popen([*CLI, "anneal", "4_1", "--out", str(tmp_path / "out"), "--overwrite"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(6)
    p.send_signal(signal.SIGINT)
    _, stderr = p.communicate(timeout=120)
    assert p.returncode == 130, stderr
    assert "Traceback" not in stderr
    assert _snapshot(tmp_path / "out") == before


# --- atlas folders: a full disk, a smaller atlas, two atlases at once (rows 4, 11) ------------


def _earlier_atlas(out: Path, knots=("3_1", "4_1", "5_1")) -> dict:
    """A folder holding an earlier (larger) atlas, and a file of the user's."""
    (out / "knots").mkdir(parents=True)
    (out / "index.html").write_text("<html>the earlier atlas</html>\n")
    (out / "atlas.json").write_text('{"knots": []}\n')
    for k in knots:
        (out / "knots" / f"{k}.html").write_text(f"<html>{k}</html>\n")
    (out / "notes.txt").write_text("a file of the user's\n")
    return _snapshot(out)


def test_atlas_pages_on_a_full_disk_keep_the_earlier_atlas(small_fs, tmp_path):
    """Row 4: a traceback (ENOSPC in the plotly writer), a truncated plotly.min.js."""
    from helpers import fill_up

    fs = small_fs("3m")
    before = _earlier_atlas(fs / "atlas")
    fill_up(fs, leave=1 << 20)  # plotly.min.js alone takes 4.9 MB
    p = _cli("atlas", "--knots", "3_1", "--stored", "--db", tmp_path / "r.db", "--out",
             fs / "atlas", cwd=tmp_path)
    _ends_in_one_error_line(p, r"error: cannot write .*atlas.*: no space left on device",
                            codes=(1,))
    assert _snapshot(fs / "atlas") == before  # no half-written page, no hidden leftover


def test_a_smaller_atlas_leaves_no_page_of_a_larger_one(tmp_path):
    """Row 11: `atlas --stored --knots 3_1` into a larger atlas's folder left its other pages
    (stale, unlinked)."""
    _earlier_atlas(tmp_path / "atlas")
    p = _cli("atlas", "--knots", "3_1", "--stored", "--db", tmp_path / "r.db", "--out",
             tmp_path / "atlas", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert sorted(q.name for q in (tmp_path / "atlas" / "knots").iterdir()) == ["3_1.html"]
    assert "the earlier atlas" not in (tmp_path / "atlas" / "index.html").read_text()
    assert (tmp_path / "atlas" / "notes.txt").read_text() == "a file of the user's\n"
    assert not [q for q in (tmp_path / "atlas").iterdir() if q.name.startswith(".")]


@pytest.mark.skipif(sys.platform == "win32", reason="flock")
def test_two_atlases_cannot_write_one_folder_at_once(tmp_path):
    """Row 11: no lock (anneal has one): two atlases with the same --out ended mixed. The
    folder is held here as a running atlas holds it (an exclusive flock on the folder)."""
    import fcntl
    import os

    out = tmp_path / "atlas"
    out.mkdir()
    fd = os.open(out, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        p = _cli("atlas", "--knots", "3_1", "--stored", "--db", tmp_path / "r.db", "--out",
                 out, cwd=tmp_path)
    finally:
        os.close(fd)
    _one_error_line(p, r"--out .*atlas is in use by another run", codes=(2,))
    assert list(out.iterdir()) == [] and not (tmp_path / "r.db").exists()


# --- warnings (row 17) ------------------------------------------------------------------------


def test_a_warning_that_reaches_the_command_line_is_one_plain_line(capsys, monkeypatch):
    """Row 17: Python's two lines naming typer/main.py:1445; now one plain line, once."""
    import importlib
    import warnings

    from stiffknots.errors import ChainWarning

    M = importlib.import_module("stiffknots.cli.main")  # the module, not the package's main()

    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)
    M._plain_warnings()
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        for _ in range(2):
            warnings.warn("the contact distance 0.122 is below 0.504: contacts are missed",
                          ChainWarning, stacklevel=1)
    err = capsys.readouterr().err
    assert err == "warning: the contact distance 0.122 is below 0.504: contacts are missed\n"


@pytest.mark.slow
def test_relax_in_a_thin_tube_says_so_in_one_plain_line(tmp_path):
    """Row 17: `relax --w-over-L 0.0008` printed the analysis's ChainWarning mid-output."""
    p = _cli("relax", DATA / "3.1.vect", "--w-over-L", "0.0008", "--moves", "1000",
             "--replicas", "1", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "Warning" not in p.stderr and "typer" not in p.stderr, p.stderr
    notes = [ln for ln in p.stdout.splitlines() if ln.startswith("note:")]
    assert len(notes) == 1 and "contacts are missed" in notes[0], p.stdout


@pytest.mark.slow
def test_a_default_thin_limit_run_prints_no_internal_warning(tmp_path):
    """Row 17: `thin-limit 4_1 --out DIR` with its defaults printed '…/typer/main.py:1445:
    ChainWarning: the contact distance 0.122 is below 0.504 …' mid-output."""
    p = _cli("thin-limit", "4_1", "--out", tmp_path / "out", cwd=tmp_path, timeout=1200)
    assert p.returncode == 0, p.stderr[-3000:]
    assert "Warning" not in p.stderr + p.stdout and "warning:" not in p.stderr


# --- races: Ctrl-C at any moment, knot checks from threads (rows 5, 10) -----------------------


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_at_any_moment_of_an_anneal_ends_in_one_line(tmp_path):
    """Row 5: Ctrl-C during `anneal 4_1` ended in a traceback in 1 of 6 tries
    ("AttributeError: 'NoneType' object has no attribute 'values'" in pool._terminate): a
    Ctrl-C at each second of a run, from the start of the workers to the last round."""
    import signal
    import time

    for delay in (1.0, 2.5, 4.0, 5.5, 7.0, 9.0, 12.0):
        p = subprocess.Popen([*CLI, "anneal", "4_1", "--rounds", "2"], cwd=tmp_path,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        time.sleep(delay)
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=120)
        assert p.returncode in (0, 130), (delay, err[-3000:])
        assert "Traceback" not in err and "Error" not in err, (delay, err[-3000:])
        assert p.returncode == 0 or err.strip().splitlines()[-1].startswith("interrupted")


@pytest.mark.slow
def test_two_anneals_in_two_threads_print_nothing_but_their_results(tmp_path):
    """Row 10: two sk.anneal calls from two threads: correct results, 'SystemError …
    _thread.RLock' tracebacks from _after_fork on stderr (the knot checks fork a child in a
    process with threads)."""
    script = """
import sys, threading
import stiffknots as sk
out = {}
def go(name, beads):
    out[name] = sk.anneal(name, beads=beads, moves=2000, replicas=2, seed=1, rounds=1)
ts = [threading.Thread(target=go, args=a) for a in (("3_1", 43), ("4_1", 47))]
for t in ts: t.start()
for t in ts: t.join()
print(sorted((k, v.knot) for k, v in out.items()))
"""
    import os

    p = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True,
                       text=True, timeout=600,
                       env={**os.environ, "STIFFKNOTS_CACHE": str(tmp_path / "cache")})
    assert p.returncode == 0, p.stderr[-3000:]
    assert p.stdout.strip() == "[('3_1', '3_1'), ('4_1', '4_1')]"
    assert p.stderr == "", p.stderr[-3000:]
