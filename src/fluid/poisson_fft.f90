!> FFT solvers of the periodic box: pressure Poisson equation, the Helmholtz equation of the
!> Crank-Nicolson viscous step, and spectral filters, all with FFTW-MPI r2c/c2r transforms.
!>
!> The discrete 7-point Laplacian L of a periodic grid is diagonal in Fourier space with the
!> eigenvalues -(kx~^2 + ky~^2 + kz~^2), kx~ = 2 sin(kx dx / 2) / dx (the "modified wavenumbers";
!> docs/physics.md section 2). Dividing by these (not by the exact k^2) makes the solution satisfy
!> the discrete equation to round-off, so the projected velocity is discretely solenoidal.
!> The same eigenvalues serve the face-centred velocity components: a shift of the grid does not
!> change the spectrum of a constant-coefficient periodic operator.
!>
!> Layout: one in-place buffer per solver, a padded real view (2(nx/2+1), ny, nz_local) and a
!> complex view (nx/2+1, nz, ny_local) in FFTW's transposed output order, so no redistribution
!> is needed beyond FFTW's own transpose. Plans are made once, at creation.
module poisson_fft
  use, intrinsic :: iso_c_binding, only: c_ptr, c_double, c_double_complex, c_intptr_t, c_f_pointer, c_int, &
                                         c_null_ptr, c_associated
  use fftw_interface, only: fftw_mpi_plan_dft_r2c_3d, fftw_mpi_plan_dft_c2r_3d, fftw_mpi_execute_dft_r2c, &
                            fftw_mpi_execute_dft_c2r, fftw_alloc_complex, fftw_free, fftw_destroy_plan, &
                            FFTW_ESTIMATE, FFTW_MEASURE, FFTW_MPI_TRANSPOSED_OUT, FFTW_MPI_TRANSPOSED_IN
  use agglo_kinds, only: wp
  use physical_constants, only: pi, two_pi
  use parallel_env, only: world
  use error_handling, only: fatal
  use fluid_grid, only: fluid_grid_t
  implicit none
  private
  public :: poisson_fft_t, poisson_create, poisson_destroy, poisson_solve, poisson_solve_in_buffer, &
            helmholtz_solve, helmholtz_solve_in_buffer, spectral_filter, fft_round_trip, spectral_weight_t, forward

  !> A weight as a function of the physical wavenumber magnitude |k| (1/m), for spectral_filter; an
  !> extension holds the weight's parameters (a filter's width), so none is kept in module state.
  type, abstract :: spectral_weight_t
  contains
    procedure(weight_at), deferred :: weight
  end type spectral_weight_t

  abstract interface
    pure real(wp) function weight_at(self, wavenumber)
      import :: wp, spectral_weight_t
      class(spectral_weight_t), intent(in) :: self
      real(wp), intent(in) :: wavenumber   !< 1/m
    end function weight_at
  end interface

  type :: poisson_fft_t
    integer :: nx = 0, ny = 0, nz = 0, nz_local = 0, ny_local = 0, y_offset = 0, nx_complex = 0
    type(c_ptr) :: buffer = c_null_ptr, forward_plan = c_null_ptr, inverse_plan = c_null_ptr
    real(c_double), pointer, contiguous :: real_view(:, :, :) => null()           !< (2(nx/2+1), ny, nz_local)
    complex(c_double_complex), pointer, contiguous :: spectral_view(:, :, :) => null()  !< (nx/2+1, nz, ny_local)
    real(wp), allocatable :: eigen_x(:), eigen_y(:), eigen_z(:)   !< modified wavenumbers squared, 1/m^2
    real(wp), allocatable :: wave_x(:), wave_y(:), wave_z(:)      !< physical wavenumbers, 1/m
    real(wp) :: normalisation = 0                                 !< 1 / (nx ny nz): FFTW is unnormalised
  end type poisson_fft_t

contains

  !> Allocate the buffer and make the plans (collective). planning = 'estimate' (deterministic
  !> plans: bit-for-bit restarts) or 'measure' (FFTW times candidates; faster, but the chosen
  !> algorithm, hence the round-off, may differ from run to run).
  subroutine poisson_create(solver, grid, planning)
    type(poisson_fft_t), intent(inout) :: solver
    type(fluid_grid_t), intent(in) :: grid
    character(len=*), intent(in) :: planning
    integer(c_int) :: flags
    integer :: i, j, k, index_shifted
    call poisson_destroy(solver)
    solver%nx = grid%nx; solver%ny = grid%ny; solver%nz = grid%nz
    solver%nz_local = grid%nz_local
    solver%ny_local = grid%slab%ny_local_spectral
    solver%y_offset = grid%slab%y_offset_spectral
    solver%nx_complex = grid%nx / 2 + 1
    solver%normalisation = 1.0_wp / (real(grid%nx, wp) * real(grid%ny, wp) * real(grid%nz, wp))
    select case (planning)
    case ('estimate'); flags = FFTW_ESTIMATE
    case ('measure'); flags = FFTW_MEASURE
    case default; call fatal('poisson_create: unknown FFT planning '''//trim(planning)//'''')
    end select
    solver%buffer = fftw_alloc_complex(max(grid%slab%complex_alloc, 1_c_intptr_t))
    call c_f_pointer(solver%buffer, solver%real_view, [2 * solver%nx_complex, grid%ny, grid%nz_local])
    call c_f_pointer(solver%buffer, solver%spectral_view, [solver%nx_complex, grid%nz, solver%ny_local])
    solver%forward_plan = fftw_mpi_plan_dft_r2c_3d(int(grid%nz, c_intptr_t), int(grid%ny, c_intptr_t), &
        int(grid%nx, c_intptr_t), solver%real_view, solver%spectral_view, world%MPI_VAL, &
        ior(flags, FFTW_MPI_TRANSPOSED_OUT))
    solver%inverse_plan = fftw_mpi_plan_dft_c2r_3d(int(grid%nz, c_intptr_t), int(grid%ny, c_intptr_t), &
        int(grid%nx, c_intptr_t), solver%spectral_view, solver%real_view, world%MPI_VAL, &
        ior(flags, FFTW_MPI_TRANSPOSED_IN))
    if (.not. (c_associated(solver%forward_plan) .and. c_associated(solver%inverse_plan))) &
        call fatal('poisson_create: FFTW could not make the plans')
    solver%real_view = 0.0_wp

    allocate(solver%eigen_x(solver%nx_complex), solver%wave_x(solver%nx_complex))
    do i = 1, solver%nx_complex
      solver%eigen_x(i) = (2.0_wp * sin(pi * (i - 1) / grid%nx) / grid%dx)**2
      solver%wave_x(i) = two_pi * (i - 1) / grid%lx
    end do
    allocate(solver%eigen_y(solver%ny_local), solver%wave_y(solver%ny_local))
    do j = 1, solver%ny_local
      index_shifted = signed_index(solver%y_offset + j - 1, grid%ny)
      solver%eigen_y(j) = (2.0_wp * sin(pi * index_shifted / grid%ny) / grid%dy)**2
      solver%wave_y(j) = two_pi * index_shifted / grid%ly
    end do
    allocate(solver%eigen_z(grid%nz), solver%wave_z(grid%nz))
    do k = 1, grid%nz
      index_shifted = signed_index(k - 1, grid%nz)
      solver%eigen_z(k) = (2.0_wp * sin(pi * index_shifted / grid%nz) / grid%dz)**2
      solver%wave_z(k) = two_pi * index_shifted / grid%lz
    end do
  end subroutine poisson_create

  !> FFT index 0..n-1 -> signed wavenumber index -n/2+1 .. n/2.
  pure integer function signed_index(index, n)
    integer, intent(in) :: index, n
    signed_index = index
    if (index > n / 2) signed_index = index - n
  end function signed_index

  subroutine poisson_destroy(solver)
    type(poisson_fft_t), intent(inout) :: solver
    if (c_associated(solver%forward_plan)) call fftw_destroy_plan(solver%forward_plan)
    if (c_associated(solver%inverse_plan)) call fftw_destroy_plan(solver%inverse_plan)
    if (c_associated(solver%buffer)) call fftw_free(solver%buffer)
    solver%forward_plan = c_null_ptr; solver%inverse_plan = c_null_ptr; solver%buffer = c_null_ptr
    solver%real_view => null(); solver%spectral_view => null()
    if (allocated(solver%eigen_x)) deallocate(solver%eigen_x, solver%eigen_y, solver%eigen_z, &
                                              solver%wave_x, solver%wave_y, solver%wave_z)
  end subroutine poisson_destroy

  !> Copy the interior of a halo field into the real view and transform forward (also the flow
  !> statistics' spectrum: spectral_view then holds the unnormalised transform).
  subroutine forward(solver, field)
    type(poisson_fft_t), intent(inout) :: solver
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer :: j, k
    do k = 1, solver%nz_local
      do j = 1, solver%ny
        solver%real_view(1:solver%nx, j, k) = field(1:solver%nx, j, k)
      end do
    end do
    call fftw_mpi_execute_dft_r2c(solver%forward_plan, solver%real_view, solver%spectral_view)
  end subroutine forward

  !> Transform back and copy the normalised result into the interior of a halo field.
  subroutine inverse(solver, field)
    type(poisson_fft_t), intent(inout) :: solver
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: j, k
    call fftw_mpi_execute_dft_c2r(solver%inverse_plan, solver%spectral_view, solver%real_view)
    do k = 1, solver%nz_local
      do j = 1, solver%ny
        field(1:solver%nx, j, k) = solver%real_view(1:solver%nx, j, k) * solver%normalisation
      end do
    end do
  end subroutine inverse

  !> Solve L solution = rhs (interiors; halos untouched) with the mean of the solution zero.
  !> rhs must have zero mean (true of a periodic divergence); its mean is dropped with k = 0.
  subroutine poisson_solve(solver, rhs, solution)
    type(poisson_fft_t), intent(inout) :: solver
    real(wp), intent(in) :: rhs(0:, 0:, 0:)
    real(wp), intent(inout) :: solution(0:, 0:, 0:)
    integer :: j, k
    do k = 1, solver%nz_local
      do j = 1, solver%ny
        solver%real_view(1:solver%nx, j, k) = rhs(1:solver%nx, j, k)
      end do
    end do
    call poisson_solve_in_buffer(solver)
    do k = 1, solver%nz_local
      do j = 1, solver%ny
        solution(1:solver%nx, j, k) = solver%real_view(1:solver%nx, j, k)
      end do
    end do
  end subroutine poisson_solve

  !> The same solve in the solver's own buffer: on entry real_view(1:nx, 1:ny, 1:nz_local) holds
  !> the right-hand side, on exit the solution (normalised, zero mean). The fluid step writes the
  !> divergence straight into real_view and reads the potential straight out of it, so the solve
  !> costs one FFT pair plus one pass over the half spectrum (target <= 1.3 FFT pairs, docs/studies/performance.md, Fluid).
  !> FFTW's 1/(nx ny nz) normalisation is folded into the spectral division (one multiply saved
  !> per grid point and no separate scaling pass).
  subroutine poisson_solve_in_buffer(solver)
    type(poisson_fft_t), intent(inout) :: solver
    integer :: i, j, k, first
    real(wp) :: eigen_yz
    call fftw_mpi_execute_dft_r2c(solver%forward_plan, solver%real_view, solver%spectral_view)
    do j = 1, solver%ny_local
      do k = 1, solver%nz
        eigen_yz = solver%eigen_y(j) + solver%eigen_z(k)
        first = 1
        if (eigen_yz == 0.0_wp) then
          ! The k = 0 mode (only where ky = kz = 0) is undetermined: the solution has zero mean.
          solver%spectral_view(1, k, j) = (0.0_wp, 0.0_wp)
          first = 2
        end if
        do i = first, solver%nx_complex
          solver%spectral_view(i, k, j) = solver%spectral_view(i, k, j) * &
                                          (-solver%normalisation / (solver%eigen_x(i) + eigen_yz))
        end do
      end do
    end do
    call fftw_mpi_execute_dft_c2r(solver%inverse_plan, solver%spectral_view, solver%real_view)
  end subroutine poisson_solve_in_buffer

  !> Solve (I - coefficient L) field = rhs in place (interior): the implicit half of
  !> Crank-Nicolson with coefficient = nu dt / 2. Positive coefficient: always solvable.
  subroutine helmholtz_solve(solver, field, coefficient)
    type(poisson_fft_t), intent(inout) :: solver
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    real(wp), intent(in) :: coefficient
    call forward(solver, field)
    call helmholtz_divide(solver, coefficient)
    call inverse(solver, field)
  end subroutine helmholtz_solve

  !> The same solve in the solver's own buffer, for callers that hold the right-hand side in
  !> another layout (the hypre preconditioner's rows): on entry real_view(1:nx, 1:ny, 1:nz_local)
  !> holds it, on exit the solution times nx ny nz (FFTW is unnormalised): the caller multiplies
  !> by solver%normalisation as it copies the solution out, exactly as helmholtz_solve does.
  subroutine helmholtz_solve_in_buffer(solver, coefficient)
    type(poisson_fft_t), intent(inout) :: solver
    real(wp), intent(in) :: coefficient
    call fftw_mpi_execute_dft_r2c(solver%forward_plan, solver%real_view, solver%spectral_view)
    call helmholtz_divide(solver, coefficient)
    call fftw_mpi_execute_dft_c2r(solver%inverse_plan, solver%spectral_view, solver%real_view)
  end subroutine helmholtz_solve_in_buffer

  !> Divide every Fourier mode of spectral_view by 1 + coefficient (kx~^2 + ky~^2 + kz~^2).
  subroutine helmholtz_divide(solver, coefficient)
    type(poisson_fft_t), intent(inout) :: solver
    real(wp), intent(in) :: coefficient
    integer :: i, j, k
    real(wp) :: eigen_yz
    do j = 1, solver%ny_local
      do k = 1, solver%nz
        eigen_yz = solver%eigen_y(j) + solver%eigen_z(k)
        do i = 1, solver%nx_complex
          solver%spectral_view(i, k, j) = solver%spectral_view(i, k, j) / (1.0_wp + coefficient * &
                                          (solver%eigen_x(i) + eigen_yz))
        end do
      end do
    end do
  end subroutine helmholtz_divide

  !> Multiply every Fourier mode of a field (interior) by weight(|k|), |k| the physical wavenumber.
  subroutine spectral_filter(solver, field, weight)
    type(poisson_fft_t), intent(inout) :: solver
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    class(spectral_weight_t), intent(in) :: weight
    integer :: i, j, k
    call forward(solver, field)
    do j = 1, solver%ny_local
      do k = 1, solver%nz
        do i = 1, solver%nx_complex
          solver%spectral_view(i, k, j) = solver%spectral_view(i, k, j) * &
              weight%weight(sqrt(solver%wave_x(i)**2 + solver%wave_y(j)**2 + solver%wave_z(k)**2))
        end do
      end do
    end do
    call inverse(solver, field)
  end subroutine spectral_filter

  !> One forward and one inverse 3-D transform of the solver's buffer, nothing else (no copies,
  !> no scaling): the yardstick the benchmark compares the Poisson solve against.
  subroutine fft_round_trip(solver)
    type(poisson_fft_t), intent(inout) :: solver
    call fftw_mpi_execute_dft_r2c(solver%forward_plan, solver%real_view, solver%spectral_view)
    call fftw_mpi_execute_dft_c2r(solver%inverse_plan, solver%spectral_view, solver%real_view)
  end subroutine fft_round_trip
end module poisson_fft
