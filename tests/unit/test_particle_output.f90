! ranks: 2
! checks: 16
!> Unit tests of particle_output on 2 ranks (rank 0 writes, rank 1's calls are no-ops): pair time series
!> rows and events round trip exactly across the in-memory buffer boundary, the h5py-visible shapes are
!> (N), (N, 3), (N, 4), an events table exists (empty) in a run without collisions, generic named columns,
!> and summary.json parses with python3's json module and holds the values written.
!> Reference: the values the test wrote (HDF5 and the 17-digit JSON numbers round trip doubles exactly).
!> Every expected value is the stored copy of what was written, never a second evaluation of the same
!> formula: under -march=native the compiler may contract one evaluation into a fused multiply-add and
!> not the other, so two evaluations can differ in the last bit.
program test_particle_output
  use agglo_kinds, only: wp, i8
  use particle_output, only: particle_output_t, pair_run_metadata_t, particle_record_t, pair_record_t, &
                             collision_event_t, run_summary_t, particle_output_open, particle_output_close, &
                             particle_output_flush, append_pair_sample, append_collision_event, sample_value, &
                             sample_end, write_summary_json
  use hdf5_files, only: h5_file_t, h5_open, h5_close, h5_exists, h5_finalize
  use hdf5_datasets, only: h5_read_scalar, h5_read_array, h5_read_string, h5_dataset_shape
  use hdf5, only: hsize_t
  use file_system, only: file_exists, delete_file
  use parallel_env, only: parallel_start, is_root, barrier
  use test_framework, only: test_start, test_finish, check
  implicit none
  integer, parameter :: n_samples = 600   ! more than two buffers of 256 rows
  type(particle_output_t) :: out
  type(pair_run_metadata_t) :: metadata
  type(particle_record_t) :: particles(2), written_particles(2, n_samples)
  type(pair_record_t) :: pair, written_pairs(n_samples)
  type(collision_event_t) :: written_events(3)
  real(wp) :: written_time(n_samples)
  type(collision_event_t) :: event
  type(run_summary_t) :: summary
  type(h5_file_t) :: file
  real(wp), allocatable :: time(:), table(:,:), column(:)
  integer(hsize_t), allocatable :: dims(:)
  character(len=:), allocatable :: text
  integer(i8) :: seed
  real(wp) :: radius
  integer :: i, status, n_events
  logical :: ok

  call parallel_start()
  call test_start('particle_output')
  metadata = pair_run_metadata_t(name='pair1', shape='needle', aspect_ratio=5.0_wp, radius=50.0e-6_wp, &
                                 fluid='stokes', seed=1234567890123_i8)
  call particle_output_open(out, 'test_particles.h5', metadata)
  n_events = 0
  do i = 1, n_samples
    call fill_sample(i)
    written_time(i) = sample_time(i)
    written_particles(:, i) = particles
    written_pairs(i) = pair
    call append_pair_sample(out, written_time(i), particles, pair)
    if (i == 100 .or. i == 400 .or. i == 401) then
      event = collision_event_t(time=written_time(i), theta1=0.1_wp * i, phi1=-0.2_wp, theta2=1.5_wp, phi2=3.0_wp, &
                                normal_velocity_before=1.0e-3_wp, normal_velocity_after=-0.5e-3_wp, psi=0.25_wp)
      call append_collision_event(out, event)
      n_events = n_events + 1
      written_events(n_events) = event
    end if
    if (i == 300) call particle_output_flush(out)
  end do
  call particle_output_close(out)
  call barrier()

  ok = .true.
  if (is_root()) then
    call h5_open(file, 'test_particles.h5', writable=.false., serial=.true.)
    call h5_read_array(file, 'time', time)
    ok = size(time) == n_samples
    if (ok) ok = all(time == written_time)
    call check(ok, 'time_rows_round_trip', 'across 256-row buffers and a flush')
    dims = h5_dataset_shape(file, 'particle2/quaternion')
    call check(all(dims == [4_hsize_t, int(n_samples, hsize_t)]), 'quaternion_shape_4_by_N', 'h5py: (N, 4)')
    call h5_read_array(file, 'particle2/position', table)
    ok = all(shape(table) == [3, n_samples])
    do i = 1, n_samples
      if (ok) ok = all(table(:, i) == written_particles(2, i)%position)
    end do
    call check(ok, 'position_rows_round_trip')
    call h5_read_array(file, 'particle1/torque_collision', table)
    call check(all(table(:, n_samples) == written_particles(1, n_samples)%torque_collision), 'torque_rows_round_trip')
    call h5_read_array(file, 'pair/gap', column)
    call check(size(column) == n_samples .and. column(77) == written_pairs(77)%gap, 'pair_gap_rows_round_trip')
    call h5_read_array(file, 'pair/closest_point2', table)
    call check(all(shape(table) == [3, n_samples]) .and. table(2, 5) == written_pairs(5)%closest_point2(2), &
               'pair_closest_point_rows')
    call h5_read_array(file, 'events/time', column)
    call check(size(column) == 3 .and. all(column == written_events%time), &
               'event_rows_round_trip')
    call h5_read_array(file, 'events/theta1', column)
    call check(all(column == written_events%theta1), 'event_angles_round_trip')
    call h5_read_string(file, 'shape', text)
    call check(text == 'needle', 'root_shape_string', text)
    call h5_read_scalar(file, 'seed', seed)
    call h5_read_scalar(file, 'radius', radius)
    call check(seed == 1234567890123_i8 .and. radius == 50.0e-6_wp, 'root_seed_and_radius')
    call h5_close(file)
    ! Seen from outside: h5dump reports the h5py shape (N, 3).
    call execute_command_line('h5dump -H -d /particle1/velocity test_particles.h5 | grep -q "( 600, 3 )"', &
                              exitstat=status)
    call check(status == 0, 'h5dump_shape_N_by_3')
  end if

  ! A run without collisions: the events table exists, empty; generic columns in a second file.
  call particle_output_open(out, 'test_particles_quiet.h5', metadata)
  call fill_sample(1)
  call append_pair_sample(out, 0.0_wp, particles, pair)
  call particle_output_close(out)
  call particle_output_open(out, 'test_particles_generic.h5', metadata)
  do i = 1, 3
    call sample_value(out, 'time', real(i, wp))
    call sample_value(out, 'cluster/centre', [real(i, wp), 0.0_wp])
    call sample_end(out)
  end do
  call particle_output_close(out)
  if (is_root()) then
    call h5_open(file, 'test_particles_quiet.h5', writable=.false., serial=.true.)
    call h5_read_array(file, 'events/psi', column)
    call check(size(column) == 0 .and. h5_exists(file, 'events/normal_velocity_after'), 'empty_events_table')
    call h5_close(file)
    call h5_open(file, 'test_particles_generic.h5', writable=.false., serial=.true.)
    call h5_read_array(file, 'cluster/centre', table)
    call check(all(shape(table) == [2, 3]) .and. table(1, 3) == 3.0_wp, 'generic_named_columns')
    call check(.not. h5_exists(file, 'events'), 'generic_file_has_no_events_table')
    call h5_close(file)
  end if

  ! summary.json
  summary = run_summary_t(name='pair "1" \ test', seed=1234567890123_i8, shape='disk', aspect_ratio=0.2_wp, &
                          fluid='none', outcome='agglomerated', outcome_settled=.true., ended_in_flight=.false., &
                          end_rule='settled', collisions=3, contact_episodes=2, has_first_collision=.true., &
                          first_collision=written_events(3), max_vdw_force=1.234567890123456789e-9_wp, final_gap=-2.0e-9_wp, &
                          final_relative_velocity=0.0_wp, psi_final=1.0_wp / 3.0_wp, end_time=2.0e-3_wp, &
                          steps=20000_i8, wall_time=0.25_wp)
  call write_summary_json('test_summary.json', summary)
  summary%has_first_collision = .false.
  summary%outcome = 'approached'
  summary%ended_in_flight = .true.
  call write_summary_json('test_summary_none.json', summary)
  if (is_root()) then
    call check(.not. file_exists('test_summary.json.tmp'), 'summary_tmp_renamed')
    open(newunit=i, file='check_summary.py', status='replace', action='write')
    write(i, '(a)') 'import json, sys'
    write(i, '(a)') 's = json.load(open("test_summary.json"))'
    write(i, '(a)') 'assert s["name"] == "pair \"1\" \\ test", s["name"]'
    write(i, '(a)') 'assert s["seed"] == 1234567890123 and s["collisions"] == 3 and s["steps"] == 20000'
    write(i, '(a)') 'assert s["outcome"] == "agglomerated" and s["shape"] == "disk" and s["fluid"] == "none"'
    write(i, '(a)') 'assert s["max_vdw_force"] == 1.234567890123456789e-9 and s["psi_final"] == 1.0 / 3.0'
    write(i, '(a)') 'assert s["final_gap"] == -2e-9 and s["aspect_ratio"] == 0.2 and s["wall_time"] == 0.25'
    write(i, '(a)') 'f = s["first_collision"]'
    ! The event's time and angle as written (17 significant digits round trip a double), not recomputed.
    write(i, '(a)') 'assert f["time"] == '//round_trip_literal(written_events(3)%time)//' and f["theta1"] == '// &
                    round_trip_literal(written_events(3)%theta1)//' and f["psi"] == 0.25'
    write(i, '(a)') 'assert f["normal_velocity_before"] == 1e-3 and f["normal_velocity_after"] == -0.5e-3'
    write(i, '(a)') 'assert s["outcome_settled"] is True and s["end_rule"] == "settled"'
    write(i, '(a)') 'assert s["ended_in_flight"] is False and s["contact_episodes"] == 2'
    write(i, '(a)') 'keys = ["name", "seed", "shape", "aspect_ratio", "fluid", "outcome", "outcome_settled",'
    write(i, '(a)') '        "ended_in_flight", "end_rule", "collisions", "contact_episodes", "first_collision",'
    write(i, '(a)') '        "max_vdw_force", "final_gap", "final_relative_velocity", "psi_final", "end_time", "steps",'
    write(i, '(a)') '        "wall_time"]'
    write(i, '(a)') 'assert list(s) == keys, list(s)'
    write(i, '(a)') 'n = json.load(open("test_summary_none.json"))'
    write(i, '(a)') 'assert n["first_collision"] is None and n["outcome"] == "approached" and n["ended_in_flight"] is True'
    write(i, '(a)') 'print("summary ok")'
    close(i)
    call execute_command_line('python3 check_summary.py', exitstat=status)
    call check(status == 0, 'summary_json_parses_with_values', 'python3 json.load, exact doubles, key order')
    call delete_file('check_summary.py')
    call delete_file('test_summary.json')
    call delete_file('test_summary_none.json')
    call delete_file('test_particles.h5')
    call delete_file('test_particles_quiet.h5')
    call delete_file('test_particles_generic.h5')
  end if
  call barrier()
  call h5_finalize()
  call test_finish()

contains

  !> x with 17 significant digits: a decimal that reads back as the same double (IEEE 754, 5.12.2).
  function round_trip_literal(x) result(text)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: text
    character(len=32) :: buffer
    write(buffer, '(es24.16e3)') x
    text = trim(adjustl(buffer))
  end function round_trip_literal

  real(wp) function sample_time(i)
    integer, intent(in) :: i
    sample_time = i * 1.0e-6_wp + 1.0_wp / 3.0_wp * 1.0e-7_wp
  end function sample_time

  !> Distinct values in every component of every record for sample i.
  subroutine fill_sample(i)
    integer, intent(in) :: i
    integer :: n
    real(wp) :: s
    s = real(i, wp)
    do n = 1, 2
      particles(n)%position = [s, 2 * s, 3 * s] * n * 1.0e-6_wp
      particles(n)%quaternion = [cos(s), sin(s), 0.0_wp, 0.0_wp]
      particles(n)%velocity = -particles(n)%position
      particles(n)%angular_velocity = [s, -s, 0.5_wp * s] / n
      particles(n)%force_hydrodynamic = [1, 2, 3] * s * n
      particles(n)%force_dlvo = [4, 5, 6] * s * n
      particles(n)%force_collision = [7, 8, 9] * s * n
      particles(n)%torque_hydrodynamic = [1, 0, 0] * s / n
      particles(n)%torque_dlvo = [0, 1, 0] * s / n
      particles(n)%torque_collision = [0, 0, 1] * s / n + n
    end do
    pair = pair_record_t(gap=-s * 1.0e-9_wp, closest_point1=[s, s, s], closest_point2=[s, 2 * s, 3 * s], &
                         chi_eta=1.0_wp / s, relative_velocity=s * 1.0e-3_wp, vdw_force=s * 1.0e-12_wp)
  end subroutine fill_sample
end program test_particle_output
