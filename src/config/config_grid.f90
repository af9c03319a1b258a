!> Namelist group &grid: the periodic box and its staggered (MAC) grid.
module config_grid
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_positive_int
  implicit none
  private
  public :: grid_config_t, read_grid_group, check_grid_group, write_grid_group, smallest_spacing

  type :: grid_config_t
    integer :: nx = 64, ny = 64, nz = 64                 !< cells per direction
    real(wp) :: length_x = 1.0e-3_wp                     !< m, periodic box edge lengths
    real(wp) :: length_y = 1.0e-3_wp
    real(wp) :: length_z = 1.0e-3_wp
  end type grid_config_t

  integer :: nx, ny, nz
  real(wp) :: length_x, length_y, length_z
  namelist /grid/ nx, ny, nz, length_x, length_y, length_z

contains

  subroutine to_namelist(cfg)
    type(grid_config_t), intent(in) :: cfg
    nx = cfg%nx; ny = cfg%ny; nz = cfg%nz
    length_x = cfg%length_x; length_y = cfg%length_y; length_z = cfg%length_z
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(grid_config_t), intent(inout) :: cfg
    cfg%nx = nx; cfg%ny = ny; cfg%nz = nz
    cfg%length_x = length_x; cfg%length_y = length_y; cfg%length_z = length_z
  end subroutine from_namelist

  subroutine read_grid_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(grid_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=grid, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'grid', ios, message)
    call from_namelist(cfg)
  end subroutine read_grid_group

  subroutine check_grid_group(cfg)
    type(grid_config_t), intent(in) :: cfg
    call require_positive_int('grid', 'nx', cfg%nx)
    call require_positive_int('grid', 'ny', cfg%ny)
    call require_positive_int('grid', 'nz', cfg%nz)
    call require_positive('grid', 'length_x', cfg%length_x)
    call require_positive('grid', 'length_y', cfg%length_y)
    call require_positive('grid', 'length_z', cfg%length_z)
  end subroutine check_grid_group

  subroutine write_grid_group(unit, cfg)
    integer, intent(in) :: unit
    type(grid_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=grid)
  end subroutine write_grid_group

  !> m, the smallest cell edge of the grid.
  pure real(wp) function smallest_spacing(cfg)
    type(grid_config_t), intent(in) :: cfg
    smallest_spacing = min(cfg%length_x / cfg%nx, cfg%length_y / cfg%ny, cfg%length_z / cfg%nz)
  end function smallest_spacing
end module config_grid
