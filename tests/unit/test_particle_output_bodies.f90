! checks: 7
!> Unit tests of particle_output for N bodies: three bodies give /particle1..3, one group per pair
!> (/pair1_2, /pair1_3, /pair2_3), /bodies and the colliding bodies in the events table; two bodies
!> keep the pair layout (/pair, no /bodies, no body columns). Reference: the values the test wrote.
program test_particle_output_bodies
  use agglo_kinds, only: wp, i8
  use particle_output, only: particle_output_t, pair_run_metadata_t, particle_record_t, pair_record_t, &
                             collision_event_t, particle_output_open, particle_output_close, &
                             append_particles_sample, append_collision_event
  use hdf5_files, only: h5_file_t, h5_open, h5_close, h5_exists, h5_finalize
  use hdf5_datasets, only: h5_read_scalar, h5_read_array
  use file_system, only: delete_file
  use parallel_env, only: parallel_start, is_root, barrier
  use test_framework, only: test_start, test_finish, check
  implicit none
  type(particle_output_t) :: out
  type(particle_record_t) :: particles(3)
  type(pair_record_t) :: pairs(3)
  type(h5_file_t) :: file
  real(wp), allocatable :: column(:), table(:,:)
  integer(i8) :: bodies
  integer :: i

  call parallel_start()
  call test_start('particle_output_bodies')
  do i = 1, 3
    particles(i)%position = real(i, wp) * [1.0_wp, 2.0_wp, 3.0_wp]
  end do
  pairs = [pair_record_t(first=1, second=2, gap=12.0e-9_wp), pair_record_t(first=1, second=3, gap=13.0e-9_wp), &
           pair_record_t(first=2, second=3, gap=23.0e-9_wp)]
  call particle_output_open(out, 'test_bodies.h5', pair_run_metadata_t(name='three', shape='sphere', bodies=3))
  call append_particles_sample(out, 0.0_wp, particles, pairs)
  call append_particles_sample(out, 1.0_wp, particles, pairs)
  call append_collision_event(out, collision_event_t(time=0.5_wp, first=2, second=3))
  call particle_output_close(out)
  call particle_output_open(out, 'test_bodies_pair.h5', pair_run_metadata_t(name='two', shape='sphere'))
  call append_particles_sample(out, 0.0_wp, particles(1:2), pairs(1:1))
  call append_collision_event(out, collision_event_t(time=0.5_wp))
  call particle_output_close(out)
  call barrier()
  if (is_root()) then
    call h5_open(file, 'test_bodies.h5', writable=.false., serial=.true.)
    call h5_read_array(file, 'particle3/position', table)
    call check(all(shape(table) == [3, 2]) .and. all(table(:, 2) == [3.0_wp, 6.0_wp, 9.0_wp]), 'third_body_rows')
    call h5_read_array(file, 'pair1_3/gap', column)
    call check(size(column) == 2 .and. column(1) == 13.0e-9_wp, 'pair_group_per_pair')
    call check(h5_exists(file, 'pair2_3/vdw_force') .and. .not. h5_exists(file, 'pair'), 'no_pair_group_for_three')
    call h5_read_scalar(file, 'bodies', bodies)
    call check(bodies == 3_i8, 'bodies_written')
    call h5_read_array(file, 'events/second', column)
    call check(size(column) == 1 .and. column(1) == 3.0_wp, 'event_bodies')
    call h5_close(file)
    call h5_open(file, 'test_bodies_pair.h5', writable=.false., serial=.true.)
    call check(h5_exists(file, 'pair/gap') .and. .not. h5_exists(file, 'pair1_2'), 'pair_layout_kept')
    call check(.not. h5_exists(file, 'bodies') .and. .not. h5_exists(file, 'events/first'), &
               'pair_layout_no_body_columns')
    call h5_close(file)
    call delete_file('test_bodies.h5')
    call delete_file('test_bodies_pair.h5')
  end if
  call barrier()
  call h5_finalize()
  call test_finish()
end program test_particle_output_bodies
