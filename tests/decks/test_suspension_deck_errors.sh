#!/usr/bin/env bash
# checks: 17
# Bad &suspension decks (&scene particles = 'suspension'; docs/decks.md, &suspension) are refused
# with the group, the variable, the value and what is allowed: before anything runs for the
# values and their combinations; at the placement, before any body is allocated, for
#  - a volume fraction random placement cannot reach: spheres at 45% (random sequential addition
#    jams near 38%, docs/theory.md "Suspension placement"), the message giving the bodies placed,
#    the fraction reached and the tries made (on 2 ranks: every rank places the same bodies and
#    stops together);
#    the same for a count (named count);
#  - more bodies than memory allows: the estimate and the limit named (&suspension memory_limit, or
#    the machine's available memory for 2.4e10 bodies), the variable the deck gives the amount by;
# and, with the resolved coupling, bodies thinner than the immersed boundary's 4 cells (a disk; a
# needle of the second species), with the grid they need.
set -u
. "$(cd "$(dirname "$0")" && pwd)/deck_error_lib.sh"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

base="&run name = 's', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'none', particles = 'suspension' /
&pair density = 2710.0 /"
expect_error() { expect_deck_error "$1" 1 "$base
$3" "$2"; }

expect_error unreachable_volume_fraction \
  "&suspension volume_fraction = 4.49771E-01 by volume (859 bodies) is not allowed; allowed: a suspension random placement reaches: it placed" \
  "&suspension volume_fraction = 0.45, max_attempts = 200 /"
grep -qE "it placed [0-9]+ bodies, volume fraction [0-9.E+-]+, after [0-9]+ tries \(max_attempts = 200 per body" \
  unreachable_volume_fraction.out && echo "PASS unreachable_volume_fraction_says_what_was_reached" || \
  echo "FAIL unreachable_volume_fraction_says_what_was_reached: $(grep -m1 'agglo: error' unreachable_volume_fraction.out)"
expect_deck_error unreachable_volume_fraction_2_ranks 2 "$base
&suspension volume_fraction = 0.45, max_attempts = 200 /" "it placed" "tries (max_attempts = 200 per body"
expect_error unreachable_count \
  "&suspension count = 4.71239E-01 by volume (900 bodies) is not allowed; allowed: a suspension random placement reaches: it placed" \
  "&suspension count = 900, max_attempts = 100 /"
expect_error memory_limit \
  "&suspension volume_fraction = 5.00000E-02 in all (95 bodies) is not allowed; allowed: bodies whose estimated memory" \
  "&suspension volume_fraction = 0.05, memory_limit = 1.0e-3 /"
grep -qE "bytes per body and 16 MiB of output buffer\) is within &suspension memory_limit \(1.0000E-003 GiB\)" memory_limit.out \
  && echo "PASS memory_limit_names_estimate_and_limit" || \
  echo "FAIL memory_limit_names_estimate_and_limit: $(grep -m1 'agglo: error' memory_limit.out)"
# 2.4e10 bodies of 0.1 um at 10%: 2e5 GiB, more than any machine has (refused before any allocation).
expect_deck_error memory_available 1 "&run name = 's', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'none', particles = 'suspension', dlvo = .false. /
&pair density = 2710.0 /
&suspension radius = 1.0e-7, volume_fraction = 0.1, min_gap = 1.0e-8 /" \
  "&suspension volume_fraction = 1.00000E-01 in all (23873241464 bodies) is not allowed; allowed: bodies whose" \
  "is within the available memory ("
expect_deck_error thin_disk_resolved 1 "&run name = 's', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'resolved', particles = 'suspension', particle_coupling = 'resolved', added_mass = .true. /
&grid nx = 32, ny = 32, nz = 32 /
&pair density = 2710.0 /
&suspension shape = 'disk', radius = 50.0e-6, aspect_ratio = 5.0, count = 4 /" \
  "&suspension radius(1) = 5.00000E-05 (disk" "a body at least 4 cells thick for the immersed boundary" \
  "&grid nx = ny = nz >= 117"
expect_deck_error thin_second_species_resolved 1 "&run name = 's', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'resolved', particles = 'suspension', particle_coupling = 'resolved', added_mass = .true. /
&grid nx = 32, ny = 32, nz = 32 /
&pair density = 2710.0 /
&suspension shape = 'sphere', 'needle', radius = 80.0e-6, 50.0e-6, aspect_ratio = 1.0, 5.0, count = 2, 4 /" \
  "&suspension radius(2) = 5.00000E-05 (needle 1.87" "a body at least 4 cells thick for the immersed boundary" \
  "&grid nx = ny = nz >= 69"
expect_error count_and_fraction "&suspension count(1) = 10 with volume_fraction(1) = 1.00000E-02 is not allowed; allowed: exactly one of count > 0 and volume_fraction > 0 per species" \
  "&suspension count = 10, volume_fraction = 0.01 /"
expect_error species_gap "&suspension shape(3) = 'disk' after an empty shape(2)" \
  "&suspension shape(1) = 'sphere', shape(3) = 'disk', count = 3*2 /"
expect_error min_gap_below_detection "&suspension min_gap = 1.00000E-10 is not allowed; allowed: > &collision detection_floor" \
  "&suspension count = 4, min_gap = 1.0e-10 /"
expect_deck_error ghost_without_collisions 1 "&run name = 's', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'none', particles = 'suspension', collisions = .false. /
&suspension count = 4, ghost = .true. /" "&suspension ghost = .true. with &scene collisions = .false. is not allowed"
expect_error body_longer_than_half_box "&suspension radius(1) = 3.00000E-04 is not allowed; allowed: a body whose longest extent" \
  "&suspension shape = 'needle', radius = 300.0e-6, count = 1 /"
# &scene substep_bodies = 'near' (docs/decks.md): the one-step update is the point particle's.
expect_deck_error near_substeps_without_point 1 "&run name = 's', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'none', particles = 'suspension', substep_bodies = 'near' /
&pair density = 2710.0 /
&suspension count = 4 /" "&scene substep_bodies = 'near' with fluid = 'none', particles = 'suspension', particle_coupling = 'resolved' is not allowed; allowed: 'all'"
expect_deck_error substep_bodies_unknown 1 "&run name = 's', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'none', particles = 'suspension', substep_bodies = 'some' /
&pair density = 2710.0 /
&suspension count = 4 /" "&scene substep_bodies = 'some' is not allowed; allowed: one of 'all' | 'near'"
expect_deck_error near_substeps_rows_between_fluid_steps 1 "&run name = 's', end_time = 1.0e-6, dt = 1.0e-5, overwrite = .true. /
&scene fluid = 'resolved', particles = 'suspension', particle_coupling = 'point', particle_substeps = 10,
       substep_bodies = 'near' /
&grid nx = 16, ny = 16, nz = 16 /
&pair density = 2710.0 /
&suspension count = 4 /
&output particle_interval = 15 /" "&output particle_interval = 15 (or stats_interval when 0) with &scene substep_bodies = 'near' is not allowed; allowed: a multiple of &scene particle_substeps = 10"
