!> The particle system's group of a checkpoint (module checkpoint_files): the state of
!> particle_system_save as datasets, read back into a system built from the same deck so that the
!> run continues bit for bit (module particle_system_state). Collective (every rank holds the whole
!> system; rank 0's values are written, every rank reads them).
!>
!> Group 'particles' (Fortran shapes; n bodies, m pairs): particles/bodies (13, n), particles/wraps
!> (3 n, integer(i8), body by body), particles/contacts (16, m), particles/dlvo (17, m),
!> particles/flags (3 m, 0 | 1, pair by pair), particles/loads (12, n), particles/counters (2, integer(i8)).
!> A system whose pair records are not the full list (1,2), (1,3), ..., (n-1,n) (more than two bodies,
!> or a periodic system's near pairs) also writes particles/pairs (2 m, first and second of each
!> record, pair by pair); a checkpoint without it holds the full list (the pair scenes' layout).
module particle_system_checkpoint
  use agglo_kinds, only: i8
  use error_handling, only: fatal
  use text_format, only: int_text
  use hdf5_files, only: h5_exists
  use hdf5_datasets, only: h5_write_array, h5_read_array
  use checkpoint_files, only: checkpoint_t
  use particle_system, only: particle_system_t
  use particle_system_state, only: particle_system_state_t, particle_system_save, particle_system_restore
  implicit none
  private
  public :: write_particle_system_checkpoint, read_particle_system_checkpoint

contains

  !> The particle system's group of an open checkpoint (checkpoint_begin .. checkpoint_commit).
  subroutine write_particle_system_checkpoint(checkpoint, system)
    type(checkpoint_t), intent(in) :: checkpoint
    type(particle_system_t), intent(in) :: system
    type(particle_system_state_t) :: state
    call particle_system_save(system, state)
    associate (file => checkpoint%file)
      call h5_write_array(file, 'particles/bodies', state%bodies)
      call h5_write_array(file, 'particles/wraps', reshape(state%wraps, [size(state%wraps)]))
      call h5_write_array(file, 'particles/contacts', state%contacts)
      call h5_write_array(file, 'particles/dlvo', state%dlvo)
      call h5_write_array(file, 'particles/flags', reshape(state%flags, [size(state%flags)]))
      call h5_write_array(file, 'particles/loads', state%loads)
      call h5_write_array(file, 'particles/counters', state%counters)
      if (system%n > 2 .or. size(system%pairs) /= system%n * (system%n - 1) / 2) &
        call h5_write_array(file, 'particles/pairs', reshape(state%pair_bodies, [size(state%pair_bodies)]))
    end associate
  end subroutine write_particle_system_checkpoint

  !> Restore system (created from the same shapes, models and box) from the particle system's group
  !> of an open checkpoint; the system is then current: do not call particle_system_interact again.
  subroutine read_particle_system_checkpoint(checkpoint, system)
    type(checkpoint_t), intent(in) :: checkpoint
    type(particle_system_t), intent(inout) :: system
    type(particle_system_state_t) :: state
    integer(i8), allocatable :: wraps(:), counters(:)
    integer, allocatable :: flags(:), pairs(:)
    integer :: m
    associate (file => checkpoint%file, path => checkpoint%path)
      if (.not. h5_exists(file, 'particles/bodies')) call fatal('checkpoint '//path// &
          ' holds no particle state (group particles): written by a run without particles?')
      call h5_read_array(file, 'particles/bodies', state%bodies)
      call h5_read_array(file, 'particles/wraps', wraps)
      call h5_read_array(file, 'particles/contacts', state%contacts)
      call h5_read_array(file, 'particles/dlvo', state%dlvo)
      call h5_read_array(file, 'particles/flags', flags)
      call h5_read_array(file, 'particles/loads', state%loads)
      call h5_read_array(file, 'particles/counters', counters)
      m = system%n * (system%n - 1) / 2
      if (h5_exists(file, 'particles/pairs')) then
        call h5_read_array(file, 'particles/pairs', pairs)
        m = size(pairs) / 2
        if (size(pairs) /= 2 * m) call fatal('checkpoint '//path//': particles/pairs holds an odd number of values')
        state%pair_bodies = reshape(pairs, [2, m])
      end if
      if (size(wraps) /= 3 * system%n .or. size(flags) /= 3 * m .or. size(counters) /= 2) &
        call fatal('checkpoint '//path//': its particle state is for another system (the deck has '// &
                   int_text(system%n)//' bodies, the checkpoint '//int_text(size(wraps) / 3)//')')
    end associate
    state%wraps = reshape(wraps, [3, system%n])
    state%flags = reshape(flags, [3, m])
    state%counters = counters
    call particle_system_restore(system, state)
  end subroutine read_particle_system_checkpoint
end module particle_system_checkpoint
