#!/usr/bin/env python3
"""Prints the 10 slowest tests of a CTest JUnit report (ctest --output-junit).

With --write-times FILE, also writes "suite seconds" lines, the measured times
that tests/CMakeLists.txt turns into the CTest labels quick, moderate and long.
"""
import argparse
import sys
import xml.etree.ElementTree as ElementTree


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("reports", nargs="+", help="JUnit XML files written by ctest --output-junit")
    parser.add_argument("--title", default="", help="what the report is of")
    parser.add_argument("--count", type=int, default=10)
    parser.add_argument("--write-times", metavar="FILE", help="write 'suite seconds' lines to FILE")
    args = parser.parse_args()

    times = {}
    for report in args.reports:
        try:
            root = ElementTree.parse(report).getroot()
        except (OSError, ElementTree.ParseError) as error:
            print(f"slowest_tests: cannot read {report}: {error}", file=sys.stderr)
            return 1
        for case in root.iter("testcase"):
            status = case.get("status", "run")
            if status == "notrun":
                continue
            # A suite measured in several reports (both builds): its longest time.
            name = case.get("name")
            times[name] = max(times.get(name, 0.0), float(case.get("time", "0")))

    ranked = sorted(times.items(), key=lambda item: -item[1])
    title = f" ({args.title})" if args.title else ""
    print(f"The {min(args.count, len(ranked))} slowest of {len(ranked)} tests{title}, "
          f"{sum(times.values()):.0f} s in all:")
    for name, seconds in ranked[: args.count]:
        print(f"  {seconds:8.1f} s  {name}")

    if args.write_times:
        with open(args.write_times, "w", encoding="utf-8") as out:
            out.write("# Measured seconds per CTest test (one per GoogleTest suite), from\n")
            out.write("# scripts/slowest_tests.py --write-times; tests/CMakeLists.txt labels\n")
            out.write("# each suite quick (< 10 s), moderate (< 60 s) or long from them, and\n")
            out.write("# CTest starts the longest first (COST). Times of several builds: the longest.\n")
            for name, seconds in sorted(times.items()):
                out.write(f"{name} {seconds:.1f}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
