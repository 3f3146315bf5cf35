#!/usr/bin/env python3
"""Replaces the text between <!-- NAME:begin --> and <!-- NAME:end --> in a Markdown file.

Usage: replace-section.py FILE NAME COMMAND TABLE_FILE
The new section reads "Command: `COMMAND`", a blank line, then the contents of TABLE_FILE.
"""
import re
import sys

path, name, command, table_file = sys.argv[1:5]
table = open(table_file).read()
text = open(path).read()
begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
if begin not in text or end not in text:
    sys.exit(f"replace-section: {path} has no {begin} ... {end} section")
block = f"{begin}\nCommand: `{command}`\n\n{table}{end}"
text = re.sub(re.escape(begin) + ".*?" + re.escape(end), lambda m: block, text, flags=re.S)
open(path, "w").write(text)
