!> Small file-system routines. Renames go through the C library's rename(), which is atomic
!> within one file system: a file written to a temporary name and renamed is either the old
!> complete file or the new complete file, never a torn one.
module file_system
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
  implicit none
  private
  public :: rename_file, file_exists, directory_exists, make_directory, delete_file

  interface
    function c_rename(old_path, new_path) bind(C, name='rename') result(status)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: old_path(*), new_path(*)
      integer(c_int) :: status
    end function c_rename
  end interface

contains

  !> Atomically rename old_path to new_path (replacing it); ok = .false. on failure.
  subroutine rename_file(old_path, new_path, ok)
    character(len=*), intent(in) :: old_path, new_path
    logical, intent(out) :: ok
    ok = (c_rename(trim(old_path)//c_null_char, trim(new_path)//c_null_char) == 0_c_int)
  end subroutine rename_file

  logical function file_exists(path)
    character(len=*), intent(in) :: path
    inquire(file=trim(path), exist=file_exists)
  end function file_exists

  logical function directory_exists(path)
    character(len=*), intent(in) :: path
    inquire(file=trim(path)//'/.', exist=directory_exists)
  end function directory_exists

  !> mkdir -p; ok tells whether the directory exists afterwards.
  subroutine make_directory(path, ok)
    character(len=*), intent(in) :: path
    logical, intent(out) :: ok
    integer :: status
    if (.not. directory_exists(path)) call execute_command_line('mkdir -p "'//trim(path)//'"', exitstat=status)
    ok = directory_exists(path)
  end subroutine make_directory

  subroutine delete_file(path)
    character(len=*), intent(in) :: path
    integer :: unit, ios
    open(newunit=unit, file=trim(path), status='old', iostat=ios)
    if (ios == 0) close(unit, status='delete')
  end subroutine delete_file
end module file_system
