!> The FFTW 3 (and FFTW-MPI) Fortran 2003 interfaces, wrapped in one module so every user
!> gets them through `use fftw_interface, only: ...` instead of including the header itself.
module fftw_interface
  use, intrinsic :: iso_c_binding
  implicit none
  include 'fftw3-mpi.f03'
end module fftw_interface
