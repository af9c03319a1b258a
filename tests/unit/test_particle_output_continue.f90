!> Unit tests of particle_output_continue (a restarted pair scene continuing particles.h5) and of
!> hdf5_files' h5_dataset_names: a file with 5 samples and 3 events, continued from 3 samples and
!> 1 event, then 2 samples and 1 event appended, holds exactly the kept rows followed by the new
!> ones, with the run identity untouched; the row counts carry on from the kept ones. 2 ranks (only
!> rank 0 writes). Reference: the values the test wrote (sample k has time k, event k time 10 k).
! ranks: 2
! checks: 11
program test_particle_output_continue
  use agglo_kinds, only: wp, i8
  use particle_output, only: particle_output_t, pair_run_metadata_t, particle_record_t, pair_record_t, &
                             collision_event_t, particle_output_open, particle_output_continue, &
                             particle_output_close, particle_output_flush, particle_output_rows, &
                             append_particles_sample, append_collision_event
  use hdf5_files, only: h5_file_t, h5_open, h5_close, h5_dataset_names, dataset_name_length, h5_finalize
  use hdf5_datasets, only: h5_read_array, h5_read_string
  use file_system, only: delete_file
  use parallel_env, only: parallel_start, is_root, barrier
  use test_framework, only: test_start, test_finish, check
  implicit none
  character(len=*), parameter :: path = 'test_continue.h5'
  type(particle_output_t) :: out
  type(particle_record_t) :: particles(2)
  type(pair_record_t) :: pair(1)
  type(h5_file_t) :: file
  character(len=dataset_name_length), allocatable :: names(:)
  character(len=:), allocatable :: name
  real(wp), allocatable :: time(:), events(:), positions(:,:)
  integer(i8) :: samples, event_rows
  integer :: k

  call parallel_start()
  call test_start('particle_output_continue')
  call particle_output_open(out, path, pair_run_metadata_t(name='kept', shape='sphere'))
  do k = 1, 5
    call sample(k)
    if (k <= 3) call append_collision_event(out, collision_event_t(time=10.0_wp * k))
  end do
  call particle_output_flush(out)
  call particle_output_rows(out, samples, event_rows)
  if (is_root()) call check(samples == 5_i8 .and. event_rows == 3_i8, 'rows_counted')
  call particle_output_close(out)

  call particle_output_continue(out, path, 2, 3_i8, 1_i8)
  call sample(6)
  call sample(7)
  call append_collision_event(out, collision_event_t(time=60.0_wp))
  call particle_output_rows(out, samples, event_rows)
  if (is_root()) call check(samples == 5_i8 .and. event_rows == 2_i8, 'rows_carried_on')
  call particle_output_close(out)
  call barrier()

  if (is_root()) then
    call h5_open(file, path, writable=.false., serial=.true.)
    call h5_read_array(file, 'time', time)
    call check(size(time) == 5, 'samples_kept_and_appended')
    if (size(time) == 5) call check(all(time == [1.0_wp, 2.0_wp, 3.0_wp, 6.0_wp, 7.0_wp]), 'samples_in_order')
    call h5_read_array(file, 'particle2/position', positions)
    call check(all(shape(positions) == [3, 5]), 'vector_columns_shrunk')
    if (size(positions, 2) == 5) call check(all(positions(1, :) == [1.0_wp, 2.0_wp, 3.0_wp, 6.0_wp, 7.0_wp]), &
                                            'vector_rows_in_order')
    call h5_read_array(file, 'events/time', events)
    call check(size(events) == 2, 'events_kept_and_appended')
    if (size(events) == 2) call check(all(events == [10.0_wp, 60.0_wp]), 'events_in_order')
    call h5_read_string(file, 'name', name)
    call check(name == 'kept', 'run_identity_kept')
    call h5_dataset_names(file, names)
    call check(any(names == 'particle1/velocity') .and. any(names == 'events/psi') .and. any(names == 'pair/gap') &
               .and. any(names == 'seed'), 'dataset_names_listed')
    ! the identity (6), time, 2 x 10 particle columns, 6 pair columns, 8 event columns
    call check(size(names) == 6 + 1 + 2 * 10 + 6 + 8, 'dataset_names_complete')
    call h5_close(file)
    call delete_file(path)
  end if
  call barrier()
  call h5_finalize()
  call test_finish()

contains

  !> Sample k: time k, every position component k.
  subroutine sample(k)
    integer, intent(in) :: k
    particles(1)%position = real(k, wp)
    particles(2)%position = real(k, wp)
    call append_particles_sample(out, real(k, wp), particles, pair)
  end subroutine sample
end program test_particle_output_continue
