!> The checks of hypre_solver, run by test_hypre_solver (1 rank) and test_hypre_solver_ranks
!> (2 ranks): the same program text on either rank count, so the two runs check the same things.
!>
!> Problems, on a 16^3 periodic box of unit edge split in z slabs:
!> - the Crank-Nicolson Helmholtz rows (I - c L_h), c = r dx^2 / 2 at viscous numbers
!>   r = nu dt / dx^2 = 0.1, 1, 10, with a manufactured solution made of discrete Fourier modes:
!>   L_h of a mode is minus its modified wavenumber squared times the mode, (2 sin(pi m / n) / dx)^2
!>   per direction, so b is known exactly without applying the assembled matrix;
!> - the same rows with lines of immersed-boundary ghost rows (1 + w_G) x_G + sum_{j /= G} w_j x_j
!>   = rhs (the pure mirror, kappa = 1, trilinear weights that include G itself and the next ghost
!>   node; the mirror cube crosses the slab boundary and the periodic wrap): non-symmetric.
module hypre_solver_checks
  use mpi_f08, only: MPI_COMM_SELF
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use parallel_env, only: global_sum, global_max, n_ranks
  use fluid_grid, only: fluid_grid_t, grid_create
  use poisson_fft, only: poisson_fft_t, poisson_create
  use hypre_solver, only: sparse_rows_t, linear_solver_config_t, solve_status_t, linear_solver_t, &
                          linear_solver_create, linear_solver_update_values, linear_solver_solve, &
                          linear_solver_destroy, solve_status_text, rows_local_count
  use hypre_helmholtz_rows, only: global_row, helmholtz_rows_create, helmholtz_rows_set_coefficient
  use hypre_fft_preconditioner, only: fft_helmholtz_preconditioner_t, fft_preconditioner_create
  use test_framework, only: check, check_below, check_equal, check_above
  implicit none
  private
  public :: run_hypre_solver_checks

  integer, parameter :: n = 16
  real(wp), parameter :: tolerance = 1.0e-10_wp
  character(len=8), parameter :: methods(2) = [character(len=8) :: 'bicgstab', 'gmres']
  character(len=9), parameter :: preconditioners(4) = [character(len=9) :: 'boomeramg', 'ilu', 'none', 'user']
  real(wp), parameter :: viscous_numbers(3) = [0.1_wp, 1.0_wp, 10.0_wp]
  character(len=4), parameter :: viscous_names(3) = [character(len=4) :: 'r0.1', 'r1', 'r10']

  type(fluid_grid_t), target, save :: grid
  type(poisson_fft_t), target, save :: fft
  type(fft_helmholtz_preconditioner_t), target, save :: fft_preconditioner

contains

  subroutine run_hypre_solver_checks()
    integer :: v
    call grid_create(grid, n, n, n, 1.0_wp, 1.0_wp, 1.0_wp)
    call poisson_create(fft, grid, 'estimate')
    do v = 1, size(viscous_numbers)
      call check_helmholtz_all_combinations(v)
    end do
    do v = 1, size(viscous_numbers)
      call check_ghost_rows_all_combinations(v)
    end do
    call check_fft_preconditioner_with_jacobi_rows()
    call check_same_solution_as_one_rank()
    call check_values_update()
    call check_non_convergence_reported()
  end subroutine run_hypre_solver_checks

  !> (a) every method x preconditioner on the CN Helmholtz rows: converged, and the error of the
  !> solution bounded by cond_2(A) tolerance = (1 + 6 r) tolerance (A symmetric positive definite,
  !> eigenvalues 1 .. 1 + 6 r), times 10 for the gap between hypre's recursive residual and the
  !> true one.
  subroutine check_helmholtz_all_combinations(v)
    integer, intent(in) :: v
    type(sparse_rows_t) :: rows
    real(wp), allocatable :: rhs(:), exact(:), solution(:)
    real(wp) :: coefficient
    integer :: m, p
    type(solve_status_t) :: status
    character(len=64) :: name
    coefficient = viscous_numbers(v) * grid%dx**2 / 2
    call helmholtz_rows_create(grid, coefficient, rows)
    call manufactured_helmholtz(grid, coefficient, exact, rhs)
    do m = 1, size(methods)
      do p = 1, size(preconditioners)
        name = 'helmholtz_'//trim(methods(m))//'_'//trim(preconditioners(p))//'_'//trim(viscous_names(v))
        call solve_once(rows, config_of(m, p), coefficient, rhs, solution, status)
        call check(status%converged, trim(name)//'_converged', solve_status_text(status, config_of(m, p)))
        call check_below(relative_error(solution, exact), 10 * (1 + 6 * viscous_numbers(v)) * tolerance, &
                         trim(name)//'_error')
      end do
    end do
  end subroutine check_helmholtz_all_combinations

  !> (b) the non-symmetric system with ghost rows: every combination converges and recovers the
  !> field the right-hand side was made from (b = A x_exact, row by row from the CSR entries).
  !> Bound: 1e3 tolerance (its conditioning is not known in closed form; measured errors are
  !> printed by the checks).
  subroutine check_ghost_rows_all_combinations(v)
    integer, intent(in) :: v
    type(sparse_rows_t) :: rows
    real(wp), allocatable :: rhs(:), exact(:), solution(:)
    real(wp) :: coefficient
    integer :: m, p
    type(solve_status_t) :: status
    character(len=64) :: name
    coefficient = viscous_numbers(v) * grid%dx**2 / 2
    call ghost_system(grid, coefficient, rows, exact, rhs)
    do m = 1, size(methods)
      do p = 1, size(preconditioners)
        name = 'ghost_rows_'//trim(methods(m))//'_'//trim(preconditioners(p))//'_'//trim(viscous_names(v))
        call solve_once(rows, config_of(m, p), coefficient, rhs, solution, status)
        call check(status%converged, trim(name)//'_converged', solve_status_text(status, config_of(m, p)))
        call check_below(relative_error(solution, exact), 1.0e3_wp * tolerance, trim(name)//'_error')
      end do
    end do
  end subroutine check_ghost_rows_all_combinations

  !> The FFT preconditioner with Jacobi on the replaced (ghost) rows, on the ghost system at r = 10.
  subroutine check_fft_preconditioner_with_jacobi_rows()
    type(sparse_rows_t) :: rows
    type(linear_solver_config_t) :: config
    type(linear_solver_t) :: solver
    type(solve_status_t) :: status
    real(wp), allocatable :: rhs(:), exact(:), solution(:)
    real(wp) :: coefficient
    integer :: m, row
    logical, allocatable :: replaced(:)
    coefficient = 10.0_wp * grid%dx**2 / 2
    call ghost_system(grid, coefficient, rows, exact, rhs)
    allocate(solution(size(rhs)))
    ! Ghost rows are the rows with 8 entries; their diagonal entry is the first.
    replaced = [(rows%row_start(row + 1) - rows%row_start(row) == 8, row = 1, size(rhs))]
    do m = 1, size(methods)
      config = config_of(m, 4)
      call fft_preconditioner_create(fft_preconditioner, grid, fft, coefficient)
      fft_preconditioner%replaced_rows = pack([(row, row = 1, size(rhs))], replaced)
      fft_preconditioner%replaced_diagonal = rows%values(rows%row_start(fft_preconditioner%replaced_rows))
      call linear_solver_create(solver, rows, config, fft_preconditioner)
      solution = 0
      call linear_solver_solve(solver, rhs, solution, status)
      call linear_solver_destroy(solver)
      call check(status%converged, 'ghost_rows_'//trim(methods(m))//'_fft_jacobi_rows_converged', &
                 solve_status_text(status, config))
      call check_below(relative_error(solution, exact), 1.0e3_wp * tolerance, &
                       'ghost_rows_'//trim(methods(m))//'_fft_jacobi_rows_error')
    end do
  end subroutine check_fft_preconditioner_with_jacobi_rows

  !> (c) the distributed solve equals a solve of the whole box on one rank (MPI_COMM_SELF) to the
  !> tolerance: both are within cond tolerance of the same discrete solution.
  subroutine check_same_solution_as_one_rank()
    type(fluid_grid_t) :: whole_box
    type(sparse_rows_t) :: rows, rows_whole
    real(wp), allocatable :: rhs(:), exact(:), solution(:), rhs_whole(:), exact_whole(:), solution_whole(:)
    type(linear_solver_config_t) :: config
    type(linear_solver_t) :: solver
    type(solve_status_t) :: status
    real(wp) :: coefficient, difference
    integer :: first
    coefficient = 1.0_wp * grid%dx**2 / 2
    call ghost_system(grid, coefficient, rows, exact, rhs)
    whole_box = grid
    whole_box%nz_local = grid%nz
    whole_box%z_offset = 0
    call ghost_system(whole_box, coefficient, rows_whole, exact_whole, rhs_whole)
    config%method = 'gmres'
    config%preconditioner = 'boomeramg'
    config%tolerance = tolerance
    call solve_once(rows, config, coefficient, rhs, solution, status)
    allocate(solution_whole(size(rhs_whole)), source=0.0_wp)
    call linear_solver_create(solver, rows_whole, config, communicator=MPI_COMM_SELF)
    call linear_solver_solve(solver, rhs_whole, solution_whole, status)
    call linear_solver_destroy(solver)
    call check(status%converged, 'one_rank_whole_box_converged', solve_status_text(status, config))
    first = rows%first_row
    difference = global_max(maxval(abs(solution - solution_whole(first:first + size(solution) - 1))))
    call check_below(difference / global_max(maxval(abs(exact))), 100 * tolerance, 'same_solution_on_1_and_2_ranks')
    call check_equal(n_ranks * size(solution), size(solution_whole), 'slabs_cover_the_whole_box')
  end subroutine check_same_solution_as_one_rank

  !> New values on the same structure (dt changed from r = 0.1 to r = 10): the updated solver
  !> solves the new system, twice in a row (the second solve reuses the preconditioner setup).
  subroutine check_values_update()
    type(sparse_rows_t) :: rows
    type(linear_solver_config_t) :: config
    type(linear_solver_t) :: solver
    type(solve_status_t) :: status
    real(wp), allocatable :: rhs(:), exact(:), solution(:)
    real(wp) :: coefficient
    integer :: repeat
    character(len=32) :: name
    config%method = 'bicgstab'
    config%preconditioner = 'ilu'
    config%tolerance = tolerance
    coefficient = 0.1_wp * grid%dx**2 / 2
    call helmholtz_rows_create(grid, coefficient, rows)
    call linear_solver_create(solver, rows, config)
    call manufactured_helmholtz(grid, coefficient, exact, rhs)
    allocate(solution(size(rhs)), source=0.0_wp)
    call linear_solver_solve(solver, rhs, solution, status)
    coefficient = 10.0_wp * grid%dx**2 / 2
    call helmholtz_rows_set_coefficient(grid, coefficient, rows)
    call linear_solver_update_values(solver, rows)
    call manufactured_helmholtz(grid, coefficient, exact, rhs)
    do repeat = 1, 2
      solution = 0.0_wp
      call linear_solver_solve(solver, rhs, solution, status)
      name = 'updated_values_solve_'//achar(iachar('0') + repeat)
      call check(status%converged, trim(name)//'_converged', solve_status_text(status, config))
      call check_below(relative_error(solution, exact), 10 * (1 + 6 * 10.0_wp) * tolerance, trim(name)//'_error')
    end do
    call linear_solver_destroy(solver)
  end subroutine check_values_update

  !> (d) an impossible setting (one iteration, tolerance 1e-14, no preconditioner, r = 10) is
  !> reported, not fatal: converged false, one iteration, the residual above the tolerance; the
  !> next solve (hypre's error flag cleared) converges as usual.
  subroutine check_non_convergence_reported()
    type(sparse_rows_t) :: rows
    type(linear_solver_config_t) :: config
    type(solve_status_t) :: status
    real(wp), allocatable :: rhs(:), exact(:), solution(:)
    real(wp) :: coefficient
    integer :: m
    character(len=:), allocatable :: text
    coefficient = 10.0_wp * grid%dx**2 / 2
    call helmholtz_rows_create(grid, coefficient, rows)
    call manufactured_helmholtz(grid, coefficient, exact, rhs)
    do m = 1, size(methods)
      config%method = methods(m)
      config%preconditioner = 'none'
      config%tolerance = 1.0e-14_wp
      config%max_iterations = 1
      call solve_once(rows, config, coefficient, rhs, solution, status)
      call check(.not. status%converged, 'impossible_'//trim(methods(m))//'_not_converged')
      call check_equal(status%iterations, 1, 'impossible_'//trim(methods(m))//'_iterations')
      call check_above(status%relative_residual, 1.0e-14_wp, 'impossible_'//trim(methods(m))//'_residual_reported')
      text = solve_status_text(status, config)
      call check(index(text, 'not converged after 1 iterations') > 0 .and. index(text, 'max_iterations 1') > 0, &
                 'impossible_'//trim(methods(m))//'_message', text)
      config%tolerance = tolerance
      config%max_iterations = 200
      call solve_once(rows, config, coefficient, rhs, solution, status)
      call check(status%converged, 'after_failure_'//trim(methods(m))//'_converges', solve_status_text(status, config))
    end do
  end subroutine check_non_convergence_reported

  ! ---------------------------------------------------------------------------------------------

  function config_of(m, p) result(config)
    integer, intent(in) :: m, p
    type(linear_solver_config_t) :: config
    config%method = methods(m)
    config%preconditioner = preconditioners(p)
    config%tolerance = tolerance
    config%max_iterations = 500
  end function config_of

  !> Create, solve from a zero initial guess, destroy.
  subroutine solve_once(rows, config, coefficient, rhs, solution, status)
    type(sparse_rows_t), intent(in) :: rows
    type(linear_solver_config_t), intent(in) :: config
    real(wp), intent(in) :: coefficient
    real(wp), intent(in) :: rhs(:)
    real(wp), allocatable, intent(out) :: solution(:)
    type(solve_status_t), intent(out) :: status
    type(linear_solver_t) :: solver
    allocate(solution(size(rhs)), source=0.0_wp)
    if (config%preconditioner == 'user') then
      call fft_preconditioner_create(fft_preconditioner, grid, fft, coefficient)
      call linear_solver_create(solver, rows, config, fft_preconditioner)
    else
      call linear_solver_create(solver, rows, config)
    end if
    call linear_solver_solve(solver, rhs, solution, status)
    call linear_solver_destroy(solver)
  end subroutine solve_once

  !> The manufactured field at global node (i, j, k): two discrete Fourier modes and a constant.
  pure real(wp) function exact_value(box, i, j, k)
    type(fluid_grid_t), intent(in) :: box
    integer, intent(in) :: i, j, k
    real(wp) :: x, y, z
    x = (i - 0.5_wp) * box%dx; y = (j - 0.5_wp) * box%dy; z = (k - 0.5_wp) * box%dz
    exact_value = first_mode(x, y, z) + second_mode(z) + 0.25_wp
  end function exact_value

  pure real(wp) function first_mode(x, y, z)
    real(wp), intent(in) :: x, y, z
    first_mode = sin(2 * pi * x + 0.3_wp) * cos(4 * pi * y) * sin(2 * pi * z + 0.1_wp)
  end function first_mode

  pure real(wp) function second_mode(z)
    real(wp), intent(in) :: z
    second_mode = 0.5_wp * cos(6 * pi * z)
  end function second_mode

  !> -L_h of exp(i 2 pi m x / L) along one direction: (2 sin(pi m / n) / h)^2 (modified wavenumber).
  pure real(wp) function modified_wavenumber_squared(m, cells, h)
    integer, intent(in) :: m, cells
    real(wp), intent(in) :: h
    modified_wavenumber_squared = (2 * sin(pi * m / cells) / h)**2
  end function modified_wavenumber_squared

  !> The manufactured solution on this rank's rows and b = (I - c L_h) x, mode by mode.
  subroutine manufactured_helmholtz(box, coefficient, exact, rhs)
    type(fluid_grid_t), intent(in) :: box
    real(wp), intent(in) :: coefficient
    real(wp), allocatable, intent(out) :: exact(:), rhs(:)
    real(wp) :: x, y, z, gain_first, gain_second
    integer :: i, j, k, row
    gain_first = 1 + coefficient * (modified_wavenumber_squared(1, box%nx, box%dx) + &
                 modified_wavenumber_squared(2, box%ny, box%dy) + modified_wavenumber_squared(1, box%nz, box%dz))
    gain_second = 1 + coefficient * modified_wavenumber_squared(3, box%nz, box%dz)
    allocate(exact(box%nx * box%ny * box%nz_local), rhs(box%nx * box%ny * box%nz_local))
    row = 0
    do k = box%z_offset + 1, box%z_offset + box%nz_local
      do j = 1, box%ny
        do i = 1, box%nx
          row = row + 1
          x = (i - 0.5_wp) * box%dx; y = (j - 0.5_wp) * box%dy; z = (k - 0.5_wp) * box%dz
          exact(row) = exact_value(box, i, j, k)
          rhs(row) = gain_first * first_mode(x, y, z) + gain_second * second_mode(z) + 0.25_wp
        end do
      end do
    end do
  end subroutine manufactured_helmholtz

  !> The Helmholtz rows with two lines of ghost rows, the manufactured field and b = A x_exact.
  !> Ghost lines: i = 3 .. 8 at (j = 5, k = nz/2) (the top plane of rank 0 on two ranks) and at
  !> (j = 9, k = nz) (the top of the box). Mirror point M = G + (0.4, 0.7, 0.6) cells: its cube
  !> holds G, the next ghost (i + 1) and nodes of the plane above (the other rank, or k = 1).
  subroutine ghost_system(box, coefficient, rows, exact, rhs)
    type(fluid_grid_t), intent(in) :: box
    real(wp), intent(in) :: coefficient
    type(sparse_rows_t), intent(out) :: rows
    real(wp), allocatable, intent(out) :: exact(:), rhs(:)
    type(sparse_rows_t) :: helmholtz
    real(wp), parameter :: offset(3) = [0.4_wp, 0.7_wp, 0.6_wp]
    integer :: i, j, k, row, entry, corner, a, b, c, column, source
    real(wp) :: weight
    call helmholtz_rows_create(box, coefficient, helmholtz)
    rows%first_row = helmholtz%first_row
    rows%last_row = helmholtz%last_row
    allocate(rows%row_start(rows_local_count(rows) + 1), rows%columns(8 * rows_local_count(rows)), &
             rows%values(8 * rows_local_count(rows)))
    row = 0
    entry = 0
    do k = box%z_offset + 1, box%z_offset + box%nz_local
      do j = 1, box%ny
        do i = 1, box%nx
          row = row + 1
          rows%row_start(row) = entry + 1
          if (is_ghost(box, i, j, k)) then
            ! (1 + w_G) x_G + sum_{j /= G} w_j x_j: the 8 trilinear corners, G's weight on the diagonal.
            do corner = 0, 7
              a = iand(corner, 1); b = iand(corner / 2, 1); c = iand(corner / 4, 1)
              weight = merge(offset(1), 1 - offset(1), a == 1) * merge(offset(2), 1 - offset(2), b == 1) * &
                       merge(offset(3), 1 - offset(3), c == 1)
              column = global_row(box, i + a, j + b, k + c)
              if (corner == 0) weight = 1 + weight
              entry = entry + 1
              rows%columns(entry) = column
              rows%values(entry) = weight
            end do
          else
            do source = helmholtz%row_start(row), helmholtz%row_start(row + 1) - 1
              entry = entry + 1
              rows%columns(entry) = helmholtz%columns(source)
              rows%values(entry) = helmholtz%values(source)
            end do
          end if
        end do
      end do
    end do
    rows%row_start(row + 1) = entry + 1
    allocate(exact(row), rhs(row))
    row = 0
    do k = box%z_offset + 1, box%z_offset + box%nz_local
      do j = 1, box%ny
        do i = 1, box%nx
          row = row + 1
          exact(row) = exact_value(box, i, j, k)
          rhs(row) = 0
          do source = rows%row_start(row), rows%row_start(row + 1) - 1
            rhs(row) = rhs(row) + rows%values(source) * value_of_row(box, rows%columns(source))
          end do
        end do
      end do
    end do
  end subroutine ghost_system

  pure logical function is_ghost(box, i, j, k)
    type(fluid_grid_t), intent(in) :: box
    integer, intent(in) :: i, j, k
    is_ghost = i >= 3 .and. i <= 8 .and. ((j == 5 .and. k == box%nz / 2) .or. (j == 9 .and. k == box%nz))
  end function is_ghost

  !> The manufactured value of the node a global row stands for (rows numbered as global_row).
  pure real(wp) function value_of_row(box, row)
    type(fluid_grid_t), intent(in) :: box
    integer, intent(in) :: row
    integer :: i, j, k
    i = 1 + modulo(row - 1, box%nx)
    j = 1 + modulo((row - 1) / box%nx, box%ny)
    k = 1 + (row - 1) / (box%nx * box%ny)
    value_of_row = exact_value(box, i, j, k)
  end function value_of_row

  !> ||x - x_exact||_2 / ||x_exact||_2 over all ranks.
  real(wp) function relative_error(solution, exact)
    real(wp), intent(in) :: solution(:), exact(:)
    relative_error = sqrt(global_sum(sum((solution - exact)**2)) / global_sum(sum(exact**2)))
  end function relative_error
end module hypre_solver_checks
