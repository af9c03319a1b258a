#!/usr/bin/env bash
# checks: 5
# The rooms' one-way dependencies (docs/design.md, "Layout"), checked by check_rooms.py (python3
# standard library) against the room order of design.md's dependency line:
#  - the repository: no module of src/ uses a module of a later room or of a sibling room;
#  - a fake repository (its own design.md and src/), so the checker is seen to fail: a backward use
#    (core using fluid), a use between the siblings fluid and particles, and a folder of src/ that
#    the dependency line does not name are each reported by name; its clean variant passes.
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
repo=$(cd "$here/../.." && pwd -P)
checker=$here/check_rooms.py
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT

if report=$(python3 "$checker" "$repo" 2>&1); then
  echo "PASS rooms_one_way_in_src"
else
  echo "FAIL rooms_one_way_in_src: backward or undocumented dependencies:"; printf '%s\n' "$report" | sed 's/^/    /'
fi

# A fake repository: core -> (fluid, particles) -> main program.
fake=$work/fake
mkdir -p "$fake/docs" "$fake/src/core" "$fake/src/fluid" "$fake/src/particles"
printf '%s\n' '# design' '`core` -> (`fluid`, `particles`) -> main program.' > "$fake/docs/design.md"
printf '%s\n' 'module kinds' '  implicit none' 'end module kinds' > "$fake/src/core/kinds.f90"
printf '%s\n' 'module grid' '  use kinds, only: wp' '  use mpi_f08' 'end module grid' > "$fake/src/fluid/grid.f90"
printf '%s\n' 'module body' '  use kinds, only: wp  ! use grid would be wrong' 'end module body' \
  > "$fake/src/particles/body.f90"
printf '%s\n' 'program main' '  use grid' '  use body' 'end program main' > "$fake/src/main.f90"

check_fake() { # name, expected line (empty: the clean tree passes)
  local name=$1 expected=$2 output status
  output=$(python3 "$checker" "$fake" 2>&1); status=$?
  if [ -z "$expected" ] && [ "$status" -eq 0 ] && [ -z "$output" ]; then
    echo "PASS $name"
  elif [ -n "$expected" ] && [ "$status" -eq 1 ] && grep -qxF "$expected" <<< "$output"; then
    echo "PASS $name"
  else
    echo "FAIL $name: status $status, expected '${expected:-nothing}', got:"; printf '%s\n' "$output" | sed 's/^/    /'
  fi
}

check_fake rooms_clean_fake_passes ''
printf '%s\n' 'module kinds' '  use grid, only: nx' 'end module kinds' > "$fake/src/core/kinds.f90"
check_fake rooms_backward_use_reported 'core/kinds uses fluid/grid'
printf '%s\n' 'module kinds' 'end module kinds' > "$fake/src/core/kinds.f90"
printf '%s\n' 'module body' '  use grid, only: nx' 'end module body' > "$fake/src/particles/body.f90"
check_fake rooms_sibling_use_reported 'particles/body uses fluid/grid'
printf '%s\n' 'module body' 'end module body' > "$fake/src/particles/body.f90"
mkdir -p "$fake/src/extras"; printf '%s\n' 'module extra' 'end module extra' > "$fake/src/extras/extra.f90"
check_fake rooms_undocumented_room_reported \
  "src/extras/extra.f90: room 'extras' is not in docs/design.md's dependency line"
