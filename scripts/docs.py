#!/usr/bin/env python3
"""Writes the documents whose numbers are measured: docs/accuracy.md,
docs/performance.md, docs/instant.md and the headline figures of README.md.

Each comes from a template in docs/templates/ (hand-written prose with
placeholders) and from the output of a run:

  figures  JSON lines that the tests append to $ATMOS_FIGURES_FILE
           (tests/figures.hpp): {"test", "name", "value", "unit", "bound"};
  bench    the `name<TAB>value<TAB>unit` lines of `atmos bench`;
  meta     facts about the run (date, commit, machine, durations), given as
           --meta key=value by scripts/docs.sh.

Normally run through `bash scripts/docs.sh`, which builds, runs the tests
that carry figures and `atmos bench`, and then this script. Standard library
only.

Placeholders, {{kind arguments}}, arguments separated by "|":

  {{fig TEST | NAME [| FORMAT]}}    one figure, with its unit
  {{range TEST | NAME [| FORMAT]}}  "min–max unit" over the matching figures
  {{min TEST | NAME [| FORMAT]}}    smallest matching figure
  {{max TEST | NAME [| FORMAT]}}    largest matching figure (by value)
  {{absmax TEST | NAME [| FORMAT]}} largest |value|, printed as |value|
  {{table TEST | NAME}}             Markdown table: test, figure, value, bound
  {{bench NAME [| FORMAT]}}         one `atmos bench` line, with its unit
  {{benchtable NAME [| EXCEPT]}}    Markdown table of matching bench lines
  {{meta KEY}}                      a fact about the run

TEST and NAME are shell-style patterns (fnmatch; "Accuracy.*", "RMS, 0 m, *");
NAME may list several, separated by ";" ("order [89]; order 1[0-2]").
FORMAT is a Python format spec (".1f", ".2e"); by default values get three
significant digits. A placeholder that matches nothing is an error (the
documents never show a stale or invented number), unless --allow-missing,
which writes "(not measured)" instead and says so.

README.md keeps its hand-written text; only the part between the lines
<!-- figures:begin --> and <!-- figures:end --> is replaced with the
rendered docs/templates/README-figures.md.in.
"""

import argparse
import datetime
import fnmatch
import json
import math
import os
import platform
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PLACEHOLDER = re.compile(r"\{\{\s*(\w+)\s+(.*?)\s*\}\}", re.S)
README_BEGIN = "<!-- figures:begin -->"
README_END = "<!-- figures:end -->"

# template file -> output file, relative to the repository root
OUTPUTS = [
    ("docs/templates/accuracy.md.in", "docs/accuracy.md"),
    ("docs/templates/performance.md.in", "docs/performance.md"),
    ("docs/templates/instant.md.in", "docs/instant.md"),
]
README_TEMPLATE = "docs/templates/README-figures.md.in"


class Missing(Exception):
    pass


def load_figures(path):
    """(test, name) -> figure; a later line replaces an earlier one (a rerun)."""
    figures = {}
    if not path:
        return figures
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line:
                continue
            try:
                record = json.loads(line)
                key = (record["test"], record["name"])
                figures[key] = {
                    "test": record["test"],
                    "name": record["name"],
                    "value": record["value"],
                    "unit": record.get("unit", ""),
                    "bound": record.get("bound", ""),
                }
            except (ValueError, KeyError, TypeError) as error:
                sys.exit(f"docs.py: {path}:{number}: not a figure record ({error})")
    return figures


def load_bench(path):
    """name -> (value, unit) from `atmos bench` output; other lines are ignored."""
    bench = {}
    if not path:
        return bench
    with open(path, encoding="utf-8") as f:
        for line in f:
            parts = line.rstrip("\n").split("\t")
            if len(parts) != 3:
                continue
            try:
                bench[parts[0]] = (float(parts[1]), parts[2])
            except ValueError:
                continue
    return bench


def format_value(value, spec=None):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    if spec:
        return format(value, spec)
    magnitude = abs(value)
    if magnitude == 0:
        return "0"
    if magnitude >= 100:
        return f"{value:.0f}"
    if magnitude >= 1e-3:
        text = f"{value:.3g}"
        return text
    return f"{value:.2e}"


def with_unit(text, unit):
    if not unit or unit in ("count", "ratio"):  # plain numbers
        return text
    if unit == "%":
        return f"{text} %"
    return f"{text} {unit}"


def split_arguments(text):
    return [part.strip() for part in text.split("|")]


class Renderer:
    def __init__(self, figures, bench, meta, allow_missing):
        self.figures = figures
        self.bench = bench
        self.meta = meta
        self.allow_missing = allow_missing
        self.missing = []

    def matching(self, test_pattern, name_pattern):
        names = [n.strip() for n in name_pattern.split(";")]
        found = [
            figure
            for (test, name), figure in self.figures.items()
            if fnmatch.fnmatchcase(test, test_pattern) and any(fnmatch.fnmatchcase(name, n) for n in names)
        ]
        if not found:
            raise Missing(f"no figure matches test '{test_pattern}', name '{name_pattern}'")
        return sorted(found, key=lambda f: (f["test"], f["name"]))

    def values(self, found):
        values = [f["value"] for f in found if f["value"] is not None]
        if not values:
            raise Missing(f"figures without a value: {found[0]['test']} {found[0]['name']}")
        return values

    def render_one(self, kind, arguments):
        args = split_arguments(arguments)
        spec = None
        if kind in ("fig", "range", "min", "max", "absmax"):
            if len(args) not in (2, 3):
                raise ValueError(f"{{{{{kind} TEST | NAME [| FORMAT]}}}} expected, got '{arguments}'")
            spec = args[2] if len(args) == 3 else None
            found = self.matching(args[0], args[1])
            unit = found[0]["unit"]
            if kind == "fig":
                if len(found) != 1:
                    names = ", ".join(f"{f['test']}/{f['name']}" for f in found)
                    raise ValueError(f"{{{{fig {arguments}}}}} matches {len(found)} figures: {names}")
                return with_unit(format_value(found[0]["value"], spec), unit)
            values = self.values(found)
            if kind == "min":
                return with_unit(format_value(min(values), spec), unit)
            if kind == "max":
                return with_unit(format_value(max(values), spec), unit)
            if kind == "absmax":
                return with_unit(format_value(max(abs(v) for v in values), spec), unit)
            low, high = format_value(min(values), spec), format_value(max(values), spec)
            return with_unit(low if low == high else f"{low}–{high}", unit)
        if kind == "table":
            if len(args) != 2:
                raise ValueError(f"{{{{table TEST | NAME}}}} expected, got '{arguments}'")
            found = self.matching(args[0], args[1])
            lines = ["| test | figure | value | bound |", "|---|---|---|---|"]
            for f in found:
                value = with_unit(format_value(f["value"]), f["unit"])
                lines.append(f"| `{f['test']}` | {f['name']} | {value} | {f['bound'] or '–'} |")
            return "\n".join(lines)
        if kind == "bench":
            if len(args) not in (1, 2):
                raise ValueError(f"{{{{bench NAME [| FORMAT]}}}} expected, got '{arguments}'")
            if args[0] not in self.bench:
                raise Missing(f"no `atmos bench` line '{args[0]}'")
            value, unit = self.bench[args[0]]
            return with_unit(format_value(value, args[1] if len(args) == 2 else None), unit)
        if kind == "benchtable":
            include = [p.strip() for p in args[0].split(";")]
            exclude = [p.strip() for p in args[1].split(";")] if len(args) > 1 else []
            names = sorted(n for n in self.bench
                           if any(fnmatch.fnmatchcase(n, p) for p in include)
                           and not any(fnmatch.fnmatchcase(n, p) for p in exclude))
            if not names:
                raise Missing(f"no `atmos bench` line matches '{args[0]}'")
            lines = ["| `atmos bench` line | value |", "|---|---|"]
            for n in names:
                value, unit = self.bench[n]
                lines.append(f"| `{n}` | {with_unit(format_value(value), unit)} |")
            return "\n".join(lines)
        if kind == "meta":
            if args[0] not in self.meta:
                raise Missing(f"no run fact '{args[0]}' (docs.sh passes it with --meta)")
            return self.meta[args[0]]
        raise ValueError(f"unknown placeholder kind '{kind}' in {{{{{kind} {arguments}}}}}")

    def render(self, text, where):
        def substitute(match):
            try:
                return self.render_one(match.group(1), match.group(2))
            except Missing as error:
                self.missing.append(f"{where}: {error}")
                return "(not measured)"
            except ValueError as error:
                sys.exit(f"docs.py: {where}: {error}")

        return PLACEHOLDER.sub(substitute, text)


def tests_in_templates(paths):
    """The gtest filter that runs every test a template quotes."""
    patterns = []
    for path in paths:
        with open(path, encoding="utf-8") as f:
            for match in PLACEHOLDER.finditer(f.read()):
                # Tables only list figures; the other placeholders say what must run.
                if match.group(1) in ("fig", "range", "min", "max", "absmax"):
                    # gtest filters know * and ? but not [...]: "Suite.[*]" (the
                    # figures of a suite's set-up) runs as "Suite.*".
                    test = split_arguments(match.group(2))[0].replace("[*]", "*")
                    if test not in patterns:
                        patterns.append(test)
    return ":".join(patterns)


def machine_facts():
    facts = {"python": platform.python_version(), "cores": str(os.cpu_count() or "?")}
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    facts["cpu"] = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    facts.setdefault("cpu", platform.processor() or "unknown")
    try:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
        facts["commit"] = commit + (" (with uncommitted changes)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        facts["commit"] = "unknown"
    facts["date"] = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return facts


def header(template):
    return (f"<!-- Generated by scripts/docs.py from {template}: edit the template, not this file, "
            f"and regenerate with `bash scripts/docs.sh`. -->\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--figures", help="JSON lines written by the tests ($ATMOS_FIGURES_FILE)")
    parser.add_argument("--bench", help="output of `atmos bench`")
    parser.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE", help="a fact about the run")
    parser.add_argument("--root", default=ROOT, help="repository root (default: this script's)")
    parser.add_argument("--list-tests", action="store_true",
                        help="print the gtest filter of the tests the templates quote, and exit")
    parser.add_argument("--allow-missing", action="store_true",
                        help="write '(not measured)' for figures the run lacks instead of failing")
    parser.add_argument("--check", action="store_true",
                        help="render into memory only and report missing figures; write nothing")
    options = parser.parse_args()

    templates = [os.path.join(options.root, t) for t, _ in OUTPUTS] + [os.path.join(options.root, README_TEMPLATE)]
    if options.list_tests:
        print(tests_in_templates(templates))
        return 0

    meta = machine_facts()
    for item in options.meta:
        key, separator, value = item.partition("=")
        if not separator:
            sys.exit(f"docs.py: --meta expects KEY=VALUE, got '{item}'")
        meta[key] = value
    renderer = Renderer(load_figures(options.figures), load_bench(options.bench), meta, options.allow_missing)

    rendered = {}
    for template, output in OUTPUTS:
        with open(os.path.join(options.root, template), encoding="utf-8") as f:
            rendered[output] = header(template) + renderer.render(f.read(), template)
    with open(os.path.join(options.root, README_TEMPLATE), encoding="utf-8") as f:
        block = renderer.render(f.read(), README_TEMPLATE).strip("\n")
    readme_path = os.path.join(options.root, "README.md")
    with open(readme_path, encoding="utf-8") as f:
        readme = f.read()
    begin, end = readme.find(README_BEGIN), readme.find(README_END)
    if begin < 0 or end < begin:
        sys.exit(f"docs.py: README.md lacks the lines {README_BEGIN} and {README_END}")
    rendered["README.md"] = (readme[:begin + len(README_BEGIN)] + "\n" + block + "\n" + readme[end:])

    if renderer.missing:
        print("docs.py: figures missing from this run:", file=sys.stderr)
        for line in renderer.missing:
            print("  " + line, file=sys.stderr)
        if not options.allow_missing:
            print("docs.py: nothing written (run the tests that record them, or pass --allow-missing)",
                  file=sys.stderr)
            return 1

    changed = []
    for output, text in rendered.items():
        path = os.path.join(options.root, output)
        old = None
        if os.path.exists(path):
            with open(path, encoding="utf-8") as f:
                old = f.read()
        if old != text:
            changed.append(output)
            if not options.check:
                with open(path, "w", encoding="utf-8") as f:
                    f.write(text)
    if options.check:
        print("docs.py: every figure present; would write " + (", ".join(changed) or "nothing"))
        return 0
    print("docs.py: wrote " + (", ".join(changed) if changed else "nothing (already up to date)"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
