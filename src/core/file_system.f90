!> Small file-system routines over system calls (file_system_c.c and the C library): no shell ever
!> sees a path, so every character of it is taken literally. Renames go through the C library's
!> rename(), which is atomic within one file system: a file written to a temporary name and renamed
!> is either the old complete file or the new complete file, never a torn one.
module file_system
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
  use, intrinsic :: iso_fortran_env, only: iostat_end, iostat_eor
  implicit none
  private
  public :: rename_file, file_exists, directory_exists, make_directory, delete_file, remove_path, read_whole_line, &
            short_name_t, open_short_name, close_short_name

  !> The longest path handed to the system: Linux's PATH_MAX is 4096 bytes with the terminating NUL.
  !> Deck variables that hold a path are one character longer, so that a longer value is refused
  !> by the deck checks rather than cut by the namelist read.
  integer, parameter, public :: longest_path = 4095

  !> Another name of a file for libraries that copy names into fixed buffers (Open MPI's MPI-IO):
  !> /proc/self/fd/<descriptor>/<file name>, through a descriptor of the file's directory that stays
  !> open until close_short_name (Linux). Where no such name can be made, path is the file's path.
  type :: short_name_t
    integer(c_int) :: descriptor = -1_c_int
    character(len=:), allocatable :: path
  end type short_name_t

  interface
    function c_rename(old_path, new_path) bind(C, name='rename') result(status)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: old_path(*), new_path(*)
      integer(c_int) :: status
    end function c_rename

    function c_make_directories(path) bind(C, name='agglo_make_directories') result(error)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int) :: error
    end function c_make_directories

    function c_remove_path(path) bind(C, name='agglo_remove_path') result(error)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int) :: error
    end function c_remove_path

    function c_open_directory(path) bind(C, name='agglo_open_directory') result(descriptor)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int) :: descriptor
    end function c_open_directory

    function c_close_directory(descriptor) bind(C, name='agglo_close_directory') result(error)
      import :: c_int
      integer(c_int), value :: descriptor
      integer(c_int) :: error
    end function c_close_directory

    subroutine c_error_text(code, buffer, capacity) bind(C, name='agglo_error_text')
      import :: c_int, c_char
      integer(c_int), value :: code
      character(kind=c_char), intent(out) :: buffer(*)
      integer(c_int), value :: capacity
    end subroutine c_error_text
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

  !> mkdir -p (a system call per missing directory); ok tells whether the directory exists
  !> afterwards, reason says why not (the system's error text).
  subroutine make_directory(path, ok, reason)
    character(len=*), intent(in) :: path
    logical, intent(out) :: ok
    character(len=:), allocatable, intent(out), optional :: reason
    integer(c_int) :: error
    error = c_make_directories(trim(path)//c_null_char)
    ok = (error == 0_c_int)
    if (present(reason)) reason = error_text(error)
  end subroutine make_directory

  !> Remove a file, or a directory if it is empty; ok = .false. (and nothing changed) otherwise.
  subroutine remove_path(path, ok)
    character(len=*), intent(in) :: path
    logical, intent(out) :: ok
    ok = (c_remove_path(trim(path)//c_null_char) == 0_c_int)
  end subroutine remove_path

  !> Remove a file if it exists (nothing happens if it does not).
  subroutine delete_file(path)
    character(len=*), intent(in) :: path
    logical :: ok
    if (file_exists(path)) call remove_path(path, ok)
  end subroutine delete_file

  !> A short name of the file path (short_name_t); the file itself need not exist yet.
  subroutine open_short_name(path, short)
    character(len=*), intent(in) :: path
    type(short_name_t), intent(out) :: short
    character(len=:), allocatable :: directory
    character(len=16) :: number
    integer :: slash
    short%path = path
    slash = index(path, '/', back=.true.)
    if (slash == len(path) .or. .not. directory_exists('/proc/self/fd')) return
    directory = '.'
    if (slash > 1) directory = path(1:slash - 1)
    if (slash == 1) directory = '/'
    short%descriptor = c_open_directory(directory//c_null_char)
    if (short%descriptor < 0_c_int) return
    write(number, '(i0)') short%descriptor
    short%path = '/proc/self/fd/'//trim(number)//'/'//path(slash + 1:)
  end subroutine open_short_name

  !> Release the directory descriptor of a short name (nothing happens if it holds none).
  subroutine close_short_name(short)
    type(short_name_t), intent(inout) :: short
    integer(c_int) :: error
    if (short%descriptor >= 0_c_int) error = c_close_directory(short%descriptor)
    short%descriptor = -1_c_int
  end subroutine close_short_name

  !> The system's text for an errno value ('' for 0).
  function error_text(code) result(text)
    integer(c_int), intent(in) :: code
    character(len=:), allocatable :: text
    character(kind=c_char) :: buffer(200)
    integer :: i
    text = ''
    if (code == 0_c_int) return
    call c_error_text(code, buffer, int(size(buffer), c_int))
    do i = 1, size(buffer)
      if (buffer(i) == c_null_char) exit
      text = text//buffer(i)
    end do
  end function error_text

  !> One record of a formatted file, whatever its length (non-advancing reads in chunks).
  subroutine read_whole_line(unit, line, ios)
    integer, intent(in) :: unit
    character(len=:), allocatable, intent(out) :: line
    integer, intent(out) :: ios
    character(len=256) :: chunk
    integer :: got
    line = ''
    do
      read(unit, '(a)', advance='no', size=got, iostat=ios) chunk
      line = line//chunk(1:got)
      if (ios == iostat_eor) then
        ios = 0
        return
      end if
      if (ios /= 0) then
        if (ios == iostat_end .and. len(line) > 0) ios = 0   ! a last line without a newline
        return
      end if
    end do
  end subroutine read_whole_line
end module file_system
