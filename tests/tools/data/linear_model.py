#!/usr/bin/python3
"""A forward model outside rsw, run through a study's model.command by the tests of
tests/tools/test_command_model_cli.cpp. In its working folder it reads parameters.json,
{"a": ..., "b": ...}, and writes features.json with

    y_sum = a + b,    y_diff = a - b

Options make it misbehave on purpose, depending on the parameter a:
  --fail-above X       a > X: a message on stderr, exit code 1
  --sleep-above X      a > X (and not failed above): sleep 60 s (for run time limits)
  --silent-below X     a < X: exit code 0 without writing features.json
  --undefined-above X  a > X: y_diff is NaN (undefined for this run), written as
                       Python's json module writes it (the bare word NaN)
  --pid-file FILE      append this process's id to FILE first
"""
import json
import os
import sys
import time


def option(name):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    return None


def above(name, value):
    limit = option(name)
    return limit is not None and value > float(limit)


def below(name, value):
    limit = option(name)
    return limit is not None and value < float(limit)


pid_file = option("--pid-file")
if pid_file is not None:
    with open(pid_file, "a") as f:
        f.write("%d\n" % os.getpid())

with open("parameters.json") as f:
    theta = json.load(f)
a, b = theta["a"], theta["b"]

if above("--fail-above", a):
    sys.stderr.write("linear_model.py: starting\n")
    sys.stderr.write("linear_model.py: a = %r is above %s\n" % (a, option("--fail-above")))
    sys.exit(1)
if above("--sleep-above", a):
    time.sleep(60)
if below("--silent-below", a):
    sys.exit(0)

features = {"y_sum": a + b, "y_diff": a - b}
if above("--undefined-above", a):
    features["y_diff"] = float("nan")
with open("features.json", "w") as f:
    json.dump(features, f)
