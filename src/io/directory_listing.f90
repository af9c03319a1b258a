!> The names of the files in a directory (standard Fortran cannot list a directory; the work is
!> done by agglo_list_directory in directory_listing_c.c, over POSIX opendir/readdir).
module directory_listing
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
  implicit none
  private
  public :: list_directory, name_length

  integer, parameter :: name_length = 256   !< longest entry name kept (POSIX NAME_MAX is 255)

  interface
    function c_list_directory(path, buffer, capacity) bind(C, name='agglo_list_directory') result(needed)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
      character(kind=c_char), intent(out) :: buffer(*)
      integer(c_int), value :: capacity
      integer(c_int) :: needed
    end function c_list_directory
  end interface

contains

  !> Entry names of directory path (without '.' and '..', in no particular order).
  !> ok = .false. (and no names) when the directory cannot be read.
  subroutine list_directory(path, names, ok)
    character(len=*), intent(in) :: path
    character(len=name_length), allocatable, intent(out) :: names(:)
    logical, intent(out) :: ok
    character(kind=c_char), allocatable :: buffer(:)
    integer :: capacity, needed, count, first, i, j, n
    capacity = 4096
    do
      allocate(buffer(capacity))
      needed = c_list_directory(trim(path)//c_null_char, buffer, int(capacity, c_int))
      if (needed <= capacity) exit
      capacity = needed + 1024   ! the directory grew or the buffer was small: retry
      deallocate(buffer)
    end do
    ok = needed >= 0
    allocate(names(0))
    if (.not. ok) return
    count = 0
    do i = 1, needed
      if (buffer(i) == new_line('a')) count = count + 1
    end do
    deallocate(names)
    allocate(names(count))
    names = ''
    n = 0
    first = 1
    do i = 1, needed
      if (buffer(i) /= new_line('a')) cycle
      n = n + 1
      do j = first, min(i - 1, first + name_length - 1)
        names(n)(j - first + 1:j - first + 1) = buffer(j)
      end do
      first = i + 1
    end do
  end subroutine list_directory
end module directory_listing
