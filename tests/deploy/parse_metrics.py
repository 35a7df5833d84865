#!/usr/bin/env python3
"""Parses a Prometheus text exposition with the reference parser (python3-prometheus-client) and
prints one line per sample: family, type, sample name, value, then label=value pairs, separated by
tabs. Exits non-zero (with the parser's message) when the text does not parse or a family is
declared twice. Used by tests/deploy/deploy_test_support.h."""
import sys

from prometheus_client.parser import text_string_to_metric_families


def main() -> int:
    with open(sys.argv[1], encoding="utf-8") as stream:
        text = stream.read()
    seen = set()
    try:
        for family in text_string_to_metric_families(text):
            if family.name in seen:
                print(f"family {family.name} declared twice", file=sys.stderr)
                return 1
            seen.add(family.name)
            for sample in family.samples:
                labels = "".join(f"\t{key}={value}" for key, value in sorted(sample.labels.items()))
                print(f"{family.name}\t{family.type}\t{sample.name}\t{sample.value!r}{labels}")
    except Exception as error:  # the parser raises ValueError and friends on malformed text
        print(f"parse error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
