!> Fluid state in files: its group of a checkpoint (everything for a bit-for-bit continuation),
!> field snapshots, and the initial field read from a file. Built on hdf5_files / hdf5_datasets /
!> checkpoint_files / field_output. All routines are collective.
!>
!> Checkpoint group 'fluid' (Fortran shapes): fluid/u, fluid/v, fluid/w, fluid/pressure,
!> fluid/explicit_old_u|v|w (nx, ny, nz); fluid/grid_shape (3); fluid/box_length (3, m);
!> fluid/time, fluid/dt_old (s); fluid/step (integer(i8)); fluid/has_history (0 | 1).
module fluid_restart
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal, input_error
  use file_system, only: file_exists
  use parallel_env, only: all_ranks
  use text_format, only: int_text, real_text, exact_real_text
  use hdf5_files, only: h5_file_t, h5_open, h5_close, h5_exists
  use hdf5_datasets, only: h5_read_scalar, h5_write_slab, h5_read_slab, h5_write_array, h5_read_array
  use checkpoint_files, only: checkpoint_t
  use field_output, only: field_snapshot_t, field_snapshot_begin, field_snapshot_add, &
                          at_cell_centre, at_x_face, at_y_face, at_z_face
  use fluid_solver, only: fluid_solver_t, fluid_exchange_velocity
  implicit none
  private
  public :: write_fluid_checkpoint, read_fluid_checkpoint, write_fluid_state, begin_fluid_snapshot, read_initial_field

  !> Relative difference below which a stored box length is the deck's (the same decimal in a deck
  !> gives the same double; this only forgives a last-digit rewrite of the same length).
  real(wp), parameter :: box_tolerance = 1.0e-12_wp

contains

  !> The fluid's group of an open checkpoint (checkpoint_begin .. checkpoint_commit).
  subroutine write_fluid_checkpoint(checkpoint, solver)
    type(checkpoint_t), intent(in) :: checkpoint
    type(fluid_solver_t), intent(in) :: solver
    call write_fluid_state(checkpoint%file, solver)
    call write_interior(checkpoint%file, 'fluid/explicit_old_u', solver%explicit_old_u, solver)
    call write_interior(checkpoint%file, 'fluid/explicit_old_v', solver%explicit_old_v, solver)
    call write_interior(checkpoint%file, 'fluid/explicit_old_w', solver%explicit_old_w, solver)
    call h5_write_array(checkpoint%file, 'fluid/dt_old', solver%dt_old)
    call h5_write_array(checkpoint%file, 'fluid/step', solver%step)
    call h5_write_array(checkpoint%file, 'fluid/has_history', merge(1, 0, solver%has_history))
  end subroutine write_fluid_checkpoint

  !> Into an open file: the velocity and pressure (fluid/u, v, w, pressure), fluid/grid_shape,
  !> fluid/box_length and fluid/time: what &fluid init = 'file' reads (read_initial_field) on any
  !> rank count.
  subroutine write_fluid_state(file, solver)
    type(h5_file_t), intent(in) :: file
    type(fluid_solver_t), intent(in) :: solver
    call write_interior(file, 'fluid/u', solver%u, solver)
    call write_interior(file, 'fluid/v', solver%v, solver)
    call write_interior(file, 'fluid/w', solver%w, solver)
    call write_interior(file, 'fluid/pressure', solver%pressure, solver)
    call h5_write_array(file, 'fluid/grid_shape', [solver%grid%nx, solver%grid%ny, solver%grid%nz])
    call h5_write_array(file, 'fluid/box_length', [solver%grid%lx, solver%grid%ly, solver%grid%lz])
    call h5_write_array(file, 'fluid/time', solver%time)
  end subroutine write_fluid_state

  subroutine write_interior(file, name, field, solver)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: field(0:, 0:, 0:)
    type(fluid_solver_t), intent(in) :: solver
    real(wp), allocatable :: interior(:, :, :)
    interior = field(1:solver%grid%nx, 1:solver%grid%ny, 1:solver%grid%nz_local)
    call h5_write_slab(file, name, interior, solver%grid%z_offset, [solver%grid%nx, solver%grid%ny, solver%grid%nz])
  end subroutine write_interior

  !> The whole solver state from the fluid's group of an open checkpoint (any rank count: the slabs
  !> are re-cut on reading).
  subroutine read_fluid_checkpoint(checkpoint, solver)
    type(checkpoint_t), intent(in) :: checkpoint
    type(fluid_solver_t), intent(inout) :: solver
    integer :: flag
    associate (file => checkpoint%file, path => checkpoint%path)
      if (.not. h5_exists(file, 'fluid/u')) call fatal('checkpoint '//path//' holds no fluid state (group fluid)')
      call require_grid(file, 'fluid/grid_shape', path, solver)
      call require_box(file, 'fluid/box_length', path, solver)
      call read_interior(file, 'fluid/u', solver%u, solver)
      call read_interior(file, 'fluid/v', solver%v, solver)
      call read_interior(file, 'fluid/w', solver%w, solver)
      call read_interior(file, 'fluid/pressure', solver%pressure, solver)
      call read_interior(file, 'fluid/explicit_old_u', solver%explicit_old_u, solver)
      call read_interior(file, 'fluid/explicit_old_v', solver%explicit_old_v, solver)
      call read_interior(file, 'fluid/explicit_old_w', solver%explicit_old_w, solver)
      call h5_read_scalar(file, 'fluid/time', solver%time)
      call h5_read_scalar(file, 'fluid/dt_old', solver%dt_old)
      call h5_read_scalar(file, 'fluid/step', solver%step)
      call h5_read_scalar(file, 'fluid/has_history', flag)
    end associate
    solver%has_history = (flag == 1)
    call fluid_exchange_velocity(solver)
  end subroutine read_fluid_checkpoint

  !> &fluid init = 'file': the velocity (and pressure if present) of a field snapshot
  !> (fields/u, ...) or of a checkpoint (fluid/u, ...) written by Agglo on any rank count.
  !> Time, step and multistep history start afresh.
  subroutine read_initial_field(solver, path)
    type(fluid_solver_t), intent(inout) :: solver
    character(len=*), intent(in) :: path
    type(h5_file_t) :: file
    character(len=:), allocatable :: group
    ! Every rank looks for itself (another node may not see the file); all stop together.
    if (.not. all_ranks(file_exists(path))) call input_error('fluid', 'init_file', ''''//trim(path)//'''', &
        'an existing file: a field snapshot (fields_*.h5) or a checkpoint of an earlier run')
    call h5_open(file, path, writable=.false.)
    if (h5_exists(file, 'fields/u')) then
      group = 'fields/'
      call require_grid(file, 'grid/shape', path, solver)
      call require_box(file, 'grid/lengths', path, solver)
    else if (h5_exists(file, 'fluid/u')) then
      group = 'fluid/'
      call require_grid(file, 'fluid/grid_shape', path, solver)
      call require_box(file, 'fluid/box_length', path, solver)
    else
      call fatal('deck: &fluid init_file = '''//trim(path)//''' holds no velocity field '// &
                 '(expected fields/u, v, w of a field snapshot or fluid/u, v, w of a checkpoint)')
    end if
    call read_interior(file, group//'u', solver%u, solver)
    call read_interior(file, group//'v', solver%v, solver)
    call read_interior(file, group//'w', solver%w, solver)
    if (h5_exists(file, group//'pressure')) call read_interior(file, group//'pressure', solver%pressure, solver)
    call h5_close(file)
    call fluid_exchange_velocity(solver)
  end subroutine read_initial_field

  subroutine require_grid(file, name, path, solver)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name, path
    type(fluid_solver_t), intent(in) :: solver
    integer, allocatable :: stored(:)
    call h5_read_array(file, name, stored)
    if (size(stored) /= 3) call fatal('file '//trim(path)//': '//name//' is not a 3-vector')
    if (any(stored /= [solver%grid%nx, solver%grid%ny, solver%grid%nz])) call fatal('file '//trim(path)// &
        ' holds a '//int_text(stored(1))//' x '//int_text(stored(2))//' x '//int_text(stored(3))// &
        ' grid, the deck''s &grid is '//int_text(solver%grid%nx)//' x '//int_text(solver%grid%ny)//' x '// &
        int_text(solver%grid%nz))
  end subroutine require_grid

  !> The box lengths stored in a file (name, 3 values in m) must be the deck's &grid length_x, y, z.
  subroutine require_box(file, name, path, solver)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name, path
    type(fluid_solver_t), intent(in) :: solver
    real(wp), allocatable :: stored(:)
    real(wp) :: deck(3)
    deck = [solver%grid%lx, solver%grid%ly, solver%grid%lz]
    if (.not. h5_exists(file, name)) call fatal('file '//trim(path)//' does not say its box size ('//name// &
        ' is missing: written by an older Agglo?), so it cannot be checked against the deck''s &grid. If it was '// &
        'written in the box of this deck, add that box to the file with the repository''s tools/add-box-size '''// &
        trim(path)//''' --box '//exact_real_text(deck(1))//' '//exact_real_text(deck(2))//' '// &
        exact_real_text(deck(3))//' (docs/decks.md, &fluid init_file)')
    call h5_read_array(file, name, stored)
    if (size(stored) /= 3) call fatal('file '//trim(path)//': '//name//' is not a 3-vector')
    if (any(abs(stored - deck) > box_tolerance * abs(deck))) call fatal('file '//trim(path)// &
        ' holds a box of '//real_text(stored(1))//' x '//real_text(stored(2))//' x '//real_text(stored(3))// &
        ' m, the deck''s &grid length_x, length_y, length_z are '//real_text(deck(1))//' x '// &
        real_text(deck(2))//' x '//real_text(deck(3))//' m')
  end subroutine require_box

  subroutine read_interior(file, name, field, solver)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    type(fluid_solver_t), intent(in) :: solver
    real(wp), allocatable :: interior(:, :, :)
    allocate(interior(solver%grid%nx, solver%grid%ny, solver%grid%nz_local))
    call h5_read_slab(file, name, interior, solver%grid%z_offset, [solver%grid%nx, solver%grid%ny, solver%grid%nz])
    field(1:solver%grid%nx, 1:solver%grid%ny, 1:solver%grid%nz_local) = interior
  end subroutine read_interior

  !> Open the snapshot fields_<step>.h5 with u, v, w (on their faces) and pressure (cell centres);
  !> the caller may add more (the bodies' surfaces: body_surface_output) before field_snapshot_end
  !> writes it and fields.xdmf.
  subroutine begin_fluid_snapshot(snapshot, solver)
    type(field_snapshot_t), intent(out) :: snapshot
    type(fluid_solver_t), intent(in) :: solver
    call field_snapshot_begin(snapshot, solver%step, solver%time, [solver%grid%nx, solver%grid%ny, solver%grid%nz], &
                              [solver%grid%lx, solver%grid%ly, solver%grid%lz])
    call add('u', solver%u, at_x_face)
    call add('v', solver%v, at_y_face)
    call add('w', solver%w, at_z_face)
    call add('pressure', solver%pressure, at_cell_centre)

  contains

    subroutine add(name, field, location)
      character(len=*), intent(in) :: name, location
      real(wp), intent(in) :: field(0:, 0:, 0:)
      real(wp), allocatable :: interior(:, :, :)
      interior = field(1:solver%grid%nx, 1:solver%grid%ny, 1:solver%grid%nz_local)
      call field_snapshot_add(snapshot, name, interior, solver%grid%z_offset, location)
    end subroutine add
  end subroutine begin_fluid_snapshot
end module fluid_restart
