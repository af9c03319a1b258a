#!/usr/bin/env bash
# Generate make dependencies between Fortran objects from their "module" and "use" statements.
# Usage: tools/fortran-deps.sh OBJDIR file.f90 ... > deps.mk
# Each object depends on the objects of the modules it uses (intrinsic and external modules,
# such as mpi_f08 or hdf5, are ignored). One module per file: object name = file base name.
set -euo pipefail
objdir=$1; shift
awk -v objdir="$objdir" '
function base(path,   b) { b = path; sub(/^.*\//, "", b); sub(/\.[fF]90$/, "", b); return b }
{
  line = tolower($0); sub(/!.*/, "", line)
  if (match(line, /^[ \t]*module[ \t]+[a-z0-9_]+[ \t]*$/)) {
    name = line; sub(/^[ \t]*module[ \t]+/, "", name); sub(/[ \t]*$/, "", name)
    if (name != "procedure") owner[name] = base(FILENAME)
  } else if (match(line, /^[ \t]*use[ \t,:]/)) {
    if (line ~ /intrinsic/) next
    name = line; sub(/^[ \t]*use[ \t]*(::)?[ \t]*/, "", name); sub(/[ \t,].*$/, "", name)
    uses[base(FILENAME) SUBSEP name] = 1
    files[base(FILENAME)] = 1
  }
}
END {
  for (key in uses) {
    split(key, part, SUBSEP)
    if ((part[2] in owner) && owner[part[2]] != part[1])
      printf "%s/%s.o: %s/%s.o\n", objdir, part[1], objdir, owner[part[2]]
  }
}' "$@" | sort -u
