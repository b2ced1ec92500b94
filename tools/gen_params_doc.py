#!/usr/bin/env python3
"""gen_params_doc.py IIRD DOC -- replaces the text between <!-- params:begin --> and
<!-- params:end --> in DOC (docs/cli.md) with `IIRD params --markdown`: the methods' parameter
tables as the binary declares them. tests/cli/test_params.sh fails when the two differ."""
import subprocess
import sys

iird, doc = sys.argv[1], sys.argv[2]
tables = subprocess.run([iird, "params", "--markdown"], check=True, capture_output=True, text=True).stdout
text = open(doc, encoding="utf-8").read()
begin, end = "<!-- params:begin -->\n", "<!-- params:end -->"
a, b = text.index(begin) + len(begin), text.index(end)
open(doc, "w", encoding="utf-8").write(text[:a] + tables.lstrip("\n") + text[b:])
print(f"{doc}: parameter tables regenerated")
