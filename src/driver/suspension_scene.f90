!> &scene particles = 'suspension': the bodies of &suspension placed at random in the periodic box
!> of &grid (module suspension_placement), with &pair density and the deck's particle models, the
!> pair work limited to the near pairs (models%interaction_gap = particle_interaction_gap: the DLVO
!> cut-off, or lubrication's outer gap). Random stream 4 of &run seed (docs/design.md): the
!> placement's centres and orientations, then the random relative velocities (&suspension
!> velocity_rms); the fluid's velocity at the centres is added by the scene loop (scene_setup
!> add_fluid_motion). Every rank draws the same numbers and places the same bodies.
module suspension_scene
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use error_handling, only: input_error, fatal
  use logger, only: log_line
  use text_format, only: int_text, real_text
  use progress_meter, only: scientific_text
  use random_stream, only: random_stream_t, stream_seed
  use parallel_env, only: global_max
  use config_suspension, only: species_count
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid
  use particle_system, only: particle_system_t, particle_system_create, particle_models_t, particle_pair_t, &
                             particle_interaction_gap
  use suspension_placement, only: placement_t, place_bodies, random_relative_velocities
  use pair_protocol, only: particle_models_of
  use run_directory, only: run_file
  use hdf5_datasets, only: h5_write_array, h5_read_array
  use checkpoint_files, only: checkpoint_t
  use agglomerate_tracking, only: agglomerate_tracker_t, agglomerate_tracker_create, write_agglomerate_checkpoint, &
                                  read_agglomerate_checkpoint
  use cluster_output, only: cluster_output_t, cluster_output_open, cluster_output_continue, cluster_output_flush, &
                            cluster_output_counts
  implicit none
  private
  public :: place_suspension, suspension_body_count, suspension_memory_estimate, suspension_stream_id
  public :: start_suspension_agglomerates, write_suspension_agglomerates, read_suspension_agglomerates, &
            suspension_species_names

  integer, parameter :: suspension_stream_id = 4
  !> Pair records per body the estimate allows for (the near pairs of a dilute suspension at the
  !> DLVO cut-off are a few per body; a dense one about 12).
  integer, parameter :: pair_records_per_body = 12

contains

  !> Bodies per species: count, or the nearest whole number to volume_fraction x box volume / body volume.
  function suspension_body_count(cfg) result(counts)
    type(agglo_config_t), intent(in) :: cfg
    integer(i8), allocatable :: counts(:)
    real(wp) :: box_volume, body_volume
    integer :: k
    allocate(counts(species_count(cfg%suspension)))
    box_volume = cfg%grid%length_x * cfg%grid%length_y * cfg%grid%length_z
    do k = 1, size(counts)
      associate (s => cfg%suspension)
        if (s%count(k) > 0) then
          counts(k) = s%count(k)
        else
          body_volume = 4.0_wp / 3.0_wp * acos(-1.0_wp) * s%radius(k)**3
          if (s%volume_fraction(k) * box_volume / body_volume > 1.0e15_wp) then
            counts(k) = 10_i8**15
          else
            counts(k) = nint(s%volume_fraction(k) * box_volume / body_volume, i8)
          end if
          if (counts(k) < 1) call input_error('suspension', 'volume_fraction('//int_text(k)//')', &
              real_text(s%volume_fraction(k)), '>= one body in the box: '//real_text(0.5_wp * body_volume / box_volume)// &
              ' or more for this radius and box')
        end if
      end associate
    end do
  end function suspension_body_count

  !> Bytes per body of the particle system (body, shape, loads, wraps, pair records, broad phase,
  !> a particles.h5 sample row); n bodies take n times this plus the 16 MiB of the sample buffer
  !> (particle_output): the estimate checked before anything is allocated.
  pure real(wp) function suspension_memory_estimate() result(per_body)
    type(rigid_body_t) :: body
    type(spheroid_t) :: shape
    type(particle_pair_t) :: pair
    per_body = (storage_size(body) + storage_size(shape) + pair_records_per_body * storage_size(pair)) / 8.0_wp
    per_body = per_body + 8.0_wp * (4 * 6 + 3 + 1)    ! four load arrays, wraps, bounding radius
    per_body = per_body + 4.0_wp * (6 + pair_records_per_body)   ! broad phase cells and pair lists
    per_body = per_body + 8.0_wp * 34                  ! one particles.h5 sample row
  end function suspension_memory_estimate

  !> The memory the run may take (bytes): &suspension memory_limit (GiB), else this machine's
  !> available memory (MemAvailable of /proc/meminfo); huge() when neither is known.
  real(wp) function memory_limit_bytes(cfg, source)
    type(agglo_config_t), intent(in) :: cfg
    character(len=:), allocatable, intent(out) :: source
    character(len=256) :: line
    integer :: unit, ios
    real(wp) :: kib
    memory_limit_bytes = huge(1.0_wp)
    source = 'no limit known'
    if (cfg%suspension%memory_limit > 0.0_wp) then
      memory_limit_bytes = cfg%suspension%memory_limit * 2.0_wp**30
      source = '&suspension memory_limit'
      return
    end if
    open(newunit=unit, file='/proc/meminfo', status='old', action='read', iostat=ios)
    if (ios /= 0) return
    do
      read(unit, '(a)', iostat=ios) line
      if (ios /= 0) exit
      if (line(1:13) /= 'MemAvailable:') cycle
      read(line(14:), *, iostat=ios) kib
      if (ios == 0) then
        memory_limit_bytes = kib * 1024.0_wp
        source = 'the available memory'
      end if
      exit
    end do
    close(unit)
  end function memory_limit_bytes

  !> The suspension's particle system (collective: every rank places the same bodies). Refused
  !> with the deck's variables named: more bodies than the memory limit allows (the estimate before
  !> any allocation), a placement that max_attempts tries per body cannot complete.
  subroutine place_suspension(cfg, system)
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(out) :: system
    integer(i8), allocatable :: counts(:)
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(random_stream_t) :: stream
    type(placement_t) :: placement
    type(particle_models_t) :: models
    character(len=:), allocatable :: source, requested, variable
    real(wp) :: box(3), estimate, limit, requested_fraction
    real(wp), allocatable :: velocities(:,:)
    integer :: k, n, i, first
    box = [cfg%grid%length_x, cfg%grid%length_y, cfg%grid%length_z]
    counts = suspension_body_count(cfg)
    estimate = real(sum(counts), wp) * suspension_memory_estimate() + 16.0_wp * 2.0_wp**20
    ! The smallest limit of the ranks (each reads its own machine's): every rank decides alike.
    limit = -global_max(-memory_limit_bytes(cfg, source))
    ! Named as the deck gives the amount: the count, or the volume fraction (with the bodies it means).
    variable = 'count'
    requested = int_text(sum(counts))//' bodies in all'
    if (any(cfg%suspension%volume_fraction > 0.0_wp)) then
      variable = 'volume_fraction'
      requested = real_text(sum(cfg%suspension%volume_fraction))//' in all ('//int_text(sum(counts))//' bodies)'
    end if
    if (estimate > limit .or. sum(counts) > huge(1) / 4) call input_error('suspension', variable, &
        requested, 'bodies whose estimated memory ('// &
        scientific_text(estimate / 2.0_wp**30)//' GiB: '//int_text(nint(suspension_memory_estimate()))// &
        ' bytes per body and 16 MiB of output buffer) is within '//source//' ('// &
        scientific_text(limit / 2.0_wp**30)//' GiB); fewer bodies, a smaller volume_fraction or a larger radius')
    n = int(sum(counts))
    allocate(shapes(n), bodies(n))
    first = 0
    do k = 1, size(counts)
      associate (s => cfg%suspension)
        if (trim(s%shape(k)) == 'sphere') then
          shapes(first + 1:first + counts(k)) = make_spheroid('sphere', s%radius(k), cfg%pair%density)
        else
          shapes(first + 1:first + counts(k)) = make_spheroid(trim(s%shape(k)), s%radius(k), cfg%pair%density, &
                                                              s%aspect_ratio(k))
        end if
      end associate
      first = first + int(counts(k))
    end do
    call stream_seed(stream, int(cfg%run%seed, i8), suspension_stream_id)
    call place_bodies(shapes, box, cfg%suspension%min_gap, cfg%suspension%max_attempts, stream, placement)
    if (.not. placement%complete) then
      requested_fraction = sum(shapes%volume) / product(box)
      variable = 'count'
      if (any(cfg%suspension%volume_fraction > 0.0_wp)) variable = 'volume_fraction'
      requested = real_text(requested_fraction)//' by volume ('//int_text(n)//' bodies)'
      call input_error('suspension', variable, requested, 'a suspension random placement reaches: it placed '// &
          int_text(placement%placed)//' bodies, volume fraction '//real_text(placement%volume_fraction)//', after '// &
          int_text(placement%attempts)//' tries (max_attempts = '//int_text(cfg%suspension%max_attempts)// &
          ' per body, min_gap = '//real_text(cfg%suspension%min_gap)//' m); random sequential addition of '// &
          'spheres jams near 0.38 (docs/theory.md, "Suspension placement")')
    end if
    velocities = random_relative_velocities(stream, shapes%mass, cfg%suspension%velocity_rms)
    do i = 1, n
      call rigid_body_of_spheroid(bodies(i), shapes(i), placement%centres(:, i), placement%quaternions(:, i), &
                                  velocities(:, i))
    end do
    models = particle_models_of(cfg)
    ! Ghost mode: the collisions counted, no impulse and no DLVO (the bodies pass through each other).
    if (cfg%suspension%ghost) then
      models%ghost = .true.
      models%dlvo = .false.
    end if
    ! The pair work of a suspension is local: only pairs within the models' reach are evaluated.
    models%interaction_gap = particle_interaction_gap(models)
    call particle_system_create(system, shapes, bodies, models, box_length=box)
    call log_line('suspension: '//int_text(n)//' bodies ('//int_text(size(counts))//' species) of density '// &
        scientific_text(cfg%pair%density)//' kg/m^3, volume fraction '//real_text(placement%volume_fraction)// &
        ', placed after '//int_text(placement%attempts)//' tries ('//int_text(placement%exact_gaps)// &
        ' exact gaps), min_gap '//scientific_text(cfg%suspension%min_gap)//' m'// &
        trim(merge('; ghost collisions', '                  ', models%ghost))//'; pair work within '// &
        scientific_text(models%interaction_gap)//' m; memory estimate '// &
        scientific_text(estimate / 2.0_wp**20)//' MiB')
  end subroutine place_suspension

  !> The species of each body (1..S, in the order place_suspension creates them: species after species).
  function suspension_species_of(cfg) result(species_of)
    type(agglo_config_t), intent(in) :: cfg
    integer, allocatable :: species_of(:)
    integer(i8), allocatable :: counts(:)
    integer :: k
    counts = suspension_body_count(cfg)
    species_of = [(spread(k, 1, int(counts(k))), k = 1, size(counts))]
  end function suspension_species_of

  !> The species' names in clusters.h5: the shape ('sphere', 'needle', ...), with _<k> added when
  !> another species has the same shape.
  function suspension_species_names(cfg) result(names)
    type(agglo_config_t), intent(in) :: cfg
    character(len=24), allocatable :: names(:)
    integer :: k, s
    s = species_count(cfg%suspension)
    allocate(names(s))
    do k = 1, s
      names(k) = cfg%suspension%shape(k)
      if (count(cfg%suspension%shape(1:s) == cfg%suspension%shape(k)) > 1) names(k) = trim(names(k))//'_'//int_text(k)
    end do
  end function suspension_species_names

  !> The agglomerates of a suspension with DLVO (module agglomerate_tracking): the tracker of its
  !> bodies and, unless the run continues a checkpoint (read_suspension_agglomerates), a new clusters.h5.
  subroutine start_suspension_agglomerates(cfg, system, tracker, output)
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(in) :: system
    type(agglomerate_tracker_t), intent(out) :: tracker
    type(cluster_output_t), intent(out) :: output
    call agglomerate_tracker_create(tracker, system, suspension_species_of(cfg), species_count(cfg%suspension))
    if (.not. cfg%run%restart) call cluster_output_open(output, run_file('clusters.h5'), system, tracker, &
                                                        suspension_species_names(cfg))
  end subroutine start_suspension_agglomerates

  !> The tracker's group of an open checkpoint and the counts of clusters.h5 (its waiting events
  !> written first); without_last_row: a finished run's extra last row is not kept.
  subroutine write_suspension_agglomerates(transaction, tracker, output, without_last_row)
    type(checkpoint_t), intent(in) :: transaction
    type(agglomerate_tracker_t), intent(inout) :: tracker
    type(cluster_output_t), intent(inout) :: output
    logical, intent(in) :: without_last_row
    call cluster_output_flush(output, tracker)
    call write_agglomerate_checkpoint(transaction, tracker)
    call h5_write_array(transaction%file, 'agglomerates/output_rows', cluster_output_counts(output, without_last_row))
  end subroutine write_suspension_agglomerates

  !> The tracker from an open checkpoint, and clusters.h5 continued from the counts it recorded.
  subroutine read_suspension_agglomerates(restart, tracker, output)
    type(checkpoint_t), intent(in) :: restart
    type(agglomerate_tracker_t), intent(inout) :: tracker
    type(cluster_output_t), intent(out) :: output
    integer(i8), allocatable :: counts(:)
    call read_agglomerate_checkpoint(restart, tracker)
    call h5_read_array(restart%file, 'agglomerates/output_rows', counts)
    if (size(counts) /= 4) call fatal('checkpoint '//restart%path//': agglomerates/output_rows is not 4 counts '// &
                                      '(written by another version?)')
    call cluster_output_continue(output, run_file('clusters.h5'), counts(1:4))
  end subroutine read_suspension_agglomerates
end module suspension_scene
