!> Text time series (rows "step value ...", '#' header lines) continued by a restarted run:
!> fluid_statistics.dat (fluid_monitor) and bodies_loads.dat (immersed_scene).
module text_series
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use file_system, only: rename_file
  implicit none
  private
  public :: drop_rows_after

contains

  !> Rewrite a text time series (rows "step value ...", '#' header lines) with its rows up to step
  !> last_step, through path.tmp and an atomic rename (a run killed meanwhile leaves the old file
  !> intact), for a restart from the checkpoint of last_step. Reading stops at the first row past
  !> last_step or the first row that is not a step and numbers_per_row numbers (a row torn by a
  !> kill): rows are written in step order and the checkpoint of last_step was written after its rows.
  subroutine drop_rows_after(path, last_step, numbers_per_row)
    character(len=*), intent(in) :: path
    integer(i8), intent(in) :: last_step
    integer, intent(in) :: numbers_per_row
    character(len=1024) :: line
    integer(i8) :: step
    real(wp) :: values(numbers_per_row)
    integer :: old_unit, new_unit, status
    logical :: renamed
    open(newunit=old_unit, file=path, status='old', action='read')
    open(newunit=new_unit, file=path//'.tmp', status='replace', action='write')
    do
      read(old_unit, '(a)', iostat=status) line
      if (status /= 0) exit
      if (line(1:1) /= '#') then
        read(line, *, iostat=status) step, values
        if (status /= 0 .or. step > last_step) exit
      end if
      write(new_unit, '(a)') trim(line)
    end do
    close(old_unit)
    close(new_unit)
    call rename_file(path//'.tmp', path, renamed)
    if (.not. renamed) call fatal('text_series: cannot rename '//path//'.tmp to '//path, collective=.false.)
  end subroutine drop_rows_after
end module text_series
