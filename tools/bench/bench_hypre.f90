!> Linear-solver benchmark (docs/studies/performance.md, "Linear solver (hypre)"): the Crank-Nicolson
!> Helmholtz system (I - c L_h) x = b of one velocity component on N^3 (hypre_helmholtz_rows),
!> c = r dx^2 / 2 at viscous numbers r = nu dt / dx^2 = 0.5, 2, 10, solved with every method x
!> preconditioner of hypre_solver (the 'user' preconditioner is the FFT Helmholtz solve).
!> b is a pseudo-random field (every Fourier mode present: a smooth manufactured b with a few
!> modes converges in as many Krylov iterations as it has distinct eigenvalues, whatever the
!> preconditioner); zero initial guess, relative tolerance 1e-10.
!>
!> Usage: mpirun -np R bench_hypre N            one line per r x method x preconditioner:
!>   N R r method preconditioner iterations assemble_ms first_solve_ms solve_ms update_ms residual
!>   assemble: the ParCSR matrix built from the rows, the vectors and the Krylov objects;
!>   first_solve: preconditioner setup + solve; solve: a second solve, new b, setup reused (the
!>   fastest of 3: the machine may be shared);
!>   update: new values of every row written into the matrix (with BoomerAMG and ILU new Krylov
!>   objects as well). Times are the slowest rank's.
!>        mpirun -np R bench_hypre N sphere        the same with a sphere of diameter L/4 (16 cells
!>   at 64^3) in the box: its ghost nodes' rows are the pure-mirror rows (1 + w_G) x_G +
!>   sum_{j /= G} w_j x_j = b_G (trilinear weights at M = 2B - G), its interior nodes' rows x = b.
!>        mpirun -np R bench_hypre N leak CYCLES   resident memory growth over CYCLES create +
!>   solve + destroy cycles (bicgstab + boomeramg) after a warm-up cycle.
program bench_hypre
  use mpi_f08, only: MPI_Wtime
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, parallel_stop, n_ranks, is_root, barrier, global_max, global_sum
  use fluid_grid, only: fluid_grid_t, grid_create
  use poisson_fft, only: poisson_fft_t, poisson_create
  use hypre_solver, only: sparse_rows_t, linear_solver_config_t, solve_status_t, linear_solver_t, &
                          linear_solver_create, linear_solver_update_values, linear_solver_solve, &
                          linear_solver_destroy, rows_local_count
  use hypre_helmholtz_rows, only: global_row, helmholtz_rows_create
  use hypre_fft_preconditioner, only: fft_helmholtz_preconditioner_t, fft_preconditioner_create
  implicit none
  character(len=8), parameter :: methods(2) = [character(len=8) :: 'bicgstab', 'gmres']
  !> 'user' is the FFT Helmholtz solve; 'user+jac' (sphere only) the same with Jacobi on the
  !> sphere's rows (fft_helmholtz_preconditioner_t%replaced_rows).
  character(len=9), parameter :: preconditioners(5) = [character(len=9) :: 'boomeramg', 'ilu', 'none', 'user', &
                                                       'user+jac']
  real(wp), parameter :: viscous_numbers(3) = [0.5_wp, 2.0_wp, 10.0_wp]
  real(wp), parameter :: sphere_centre(3) = [0.513_wp, 0.497_wp, 0.521_wp]   !< off the grid's symmetry
  real(wp), parameter :: sphere_radius = 0.125_wp
  integer, parameter :: solve_repeats = 3     !< the second solve is timed this often; the fastest counts
  type(fluid_grid_t), target :: grid
  type(poisson_fft_t), target :: fft
  type(fft_helmholtz_preconditioner_t), target :: fft_preconditioner
  character(len=32) :: argument
  integer :: n, cycles, v, m, p
  logical :: with_sphere = .false., sphere_reported = .false.

  call parallel_start()
  call get_command_argument(1, argument); read(argument, *) n
  call grid_create(grid, n, n, n, 1.0_wp, 1.0_wp, 1.0_wp)
  call get_command_argument(2, argument)
  if (argument == 'leak') then
    call get_command_argument(3, argument); read(argument, *) cycles
    call measure_leak(cycles)
  else
    with_sphere = (argument == 'sphere')
    call poisson_create(fft, grid, 'estimate')
    do v = 1, size(viscous_numbers)
      do m = 1, size(methods)
        do p = 1, size(preconditioners)
          if (preconditioners(p) == 'user+jac' .and. .not. with_sphere) cycle
          call measure(viscous_numbers(v), methods(m), preconditioners(p))
        end do
      end do
    end do
  end if
  call parallel_stop()

contains

  subroutine measure(viscous_number, method, preconditioner)
    real(wp), intent(in) :: viscous_number
    character(len=*), intent(in) :: method, preconditioner
    type(sparse_rows_t) :: rows
    type(linear_solver_config_t) :: config
    type(linear_solver_t) :: solver
    type(solve_status_t) :: status
    real(wp), allocatable :: rhs(:), solution(:)
    real(wp) :: coefficient, t_assemble, t_first, t_solve, t_update, t
    integer :: repeat
    coefficient = viscous_number * grid%dx**2 / 2
    config%method = method
    config%preconditioner = preconditioner
    if (preconditioner == 'user+jac') config%preconditioner = 'user'
    config%tolerance = 1.0e-10_wp
    config%max_iterations = 1000
    call helmholtz_rows_create(grid, coefficient, rows)
    if (with_sphere) call add_sphere_rows(rows)
    allocate(rhs(rows_local_count(rows)), solution(rows_local_count(rows)))

    call start_clock(t_assemble)
    if (config%preconditioner == 'user') then
      call fft_preconditioner_create(fft_preconditioner, grid, fft, coefficient)
      if (preconditioner == 'user+jac') call mark_solid_rows(rows, fft_preconditioner)
      call linear_solver_create(solver, rows, config, fft_preconditioner)
    else
      call linear_solver_create(solver, rows, config)
    end if
    call stop_clock(t_assemble)

    call pseudo_random(rows, 1, rhs)
    solution = 0
    call start_clock(t_first)
    call linear_solver_solve(solver, rhs, solution, status)
    call stop_clock(t_first)

    call pseudo_random(rows, 2, rhs)
    t_solve = huge(1.0_wp)
    do repeat = 1, solve_repeats
      solution = 0
      call start_clock(t)
      call linear_solver_solve(solver, rhs, solution, status)
      call stop_clock(t)
      t_solve = min(t_solve, t)
    end do

    ! The same values again through the update path (what a new dt or moved ghost weights cost).
    call start_clock(t_update)
    call linear_solver_update_values(solver, rows)
    call stop_clock(t_update)
    call linear_solver_destroy(solver)

    if (is_root()) write(*, '(i5,i3,f6.1,1x,a9,a10,i6,4f12.1,es10.2,l3)') n, n_ranks, viscous_number, method, &
        preconditioner, status%iterations, 1.0e3_wp * t_assemble, 1.0e3_wp * t_first, 1.0e3_wp * t_solve, &
        1.0e3_wp * t_update, status%relative_residual, status%converged
  end subroutine measure

  !> Replace the rows of the nodes inside a sphere (diameter L/4, centre off the grid's symmetry)
  !> by ghost rows (solid nodes with a fluid 6-neighbour) and identity rows (the other solid nodes).
  subroutine add_sphere_rows(rows)
    type(sparse_rows_t), intent(inout) :: rows
    type(sparse_rows_t) :: helmholtz
    real(wp) :: node(3), mirror(3), cube(3), fraction(3), weight, distance
    integer :: i, j, k, row, entry, source, corner, offset(3), base(3), ghosts, column
    integer, parameter :: neighbours(3, 6) = reshape([1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1], [3, 6])
    helmholtz = rows
    deallocate(rows%columns, rows%values)
    allocate(rows%columns(9 * rows_local_count(rows)), rows%values(9 * rows_local_count(rows)))
    row = 0
    entry = 0
    ghosts = 0
    do k = grid%z_offset + 1, grid%z_offset + grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          row = row + 1
          rows%row_start(row) = entry + 1
          node = ([i, j, k] - 0.5_wp) * grid%dx
          if (.not. inside(node)) then
            do source = helmholtz%row_start(row), helmholtz%row_start(row + 1) - 1
              entry = entry + 1
              rows%columns(entry) = helmholtz%columns(source)
              rows%values(entry) = helmholtz%values(source)
            end do
          else if (all([(inside(node + neighbours(:, corner) * grid%dx), corner = 1, 6)])) then
            entry = entry + 1
            rows%columns(entry) = global_row(grid, i, j, k)
            rows%values(entry) = 1
          else
            ! Mirror point M = 2B - G of the closest surface point B; trilinear weights on the
            ! 8 nodes around M (node (a, b, c) sits at ((a, b, c) - 1/2) dx); the diagonal is
            ! 1, plus G's own weight if G is one of the 8.
            ghosts = ghosts + 1
            distance = norm2(node - sphere_centre)
            mirror = sphere_centre + (2 * sphere_radius - distance) * (node - sphere_centre) / distance
            cube = mirror / grid%dx + 0.5_wp
            base = floor(cube)
            fraction = cube - base
            entry = entry + 1
            rows%columns(entry) = global_row(grid, i, j, k)
            rows%values(entry) = 1
            do corner = 0, 7
              offset = [iand(corner, 1), iand(corner / 2, 1), iand(corner / 4, 1)]
              weight = product(merge(fraction, 1 - fraction, offset == 1))
              column = global_row(grid, base(1) + offset(1), base(2) + offset(2), base(3) + offset(3))
              if (column == rows%columns(rows%row_start(row))) then
                rows%values(rows%row_start(row)) = 1 + weight
              else
                entry = entry + 1
                rows%columns(entry) = column
                rows%values(entry) = weight
              end if
            end do
          end if
        end do
      end do
    end do
    rows%row_start(row + 1) = entry + 1
    ghosts = nint(global_sum(real(ghosts, wp)))
    if (is_root() .and. .not. sphere_reported) write(*, '(a,i0,a)') 'sphere: ', ghosts, ' ghost rows'
    sphere_reported = .true.
  end subroutine add_sphere_rows

  !> The rows whose diagonal is not the Helmholtz one (ghost and interior rows) get Jacobi.
  subroutine mark_solid_rows(rows, preconditioner)
    type(sparse_rows_t), intent(in) :: rows
    type(fft_helmholtz_preconditioner_t), intent(inout) :: preconditioner
    integer :: row
    logical, allocatable :: replaced(:)
    real(wp), allocatable :: diagonal(:)
    allocate(replaced(rows_local_count(rows)), diagonal(rows_local_count(rows)))
    do row = 1, rows_local_count(rows)
      diagonal(row) = sum(rows%values(rows%row_start(row):rows%row_start(row + 1) - 1), &
          mask=rows%columns(rows%row_start(row):rows%row_start(row + 1) - 1) == rows%first_row + row - 1)
      replaced(row) = rows%row_start(row + 1) - rows%row_start(row) /= 7
    end do
    preconditioner%replaced_rows = pack([(row, row = 1, size(replaced))], replaced)
    preconditioner%replaced_diagonal = pack(diagonal, replaced)
  end subroutine mark_solid_rows

  pure logical function inside(point)
    real(wp), intent(in) :: point(3)
    inside = norm2(point - sphere_centre) < sphere_radius
  end function inside

  !> Resident memory (kB, from /proc/self/status) before and after many create-solve-destroy cycles.
  subroutine measure_leak(cycles)
    integer, intent(in) :: cycles
    type(sparse_rows_t) :: rows
    type(linear_solver_config_t) :: config
    type(linear_solver_t) :: solver
    type(solve_status_t) :: status
    real(wp), allocatable :: rhs(:), solution(:)
    integer :: cycle_number, memory_before, memory_after
    call helmholtz_rows_create(grid, 1.0_wp * grid%dx**2, rows)
    allocate(rhs(rows_local_count(rows)), solution(rows_local_count(rows)))
    call pseudo_random(rows, 1, rhs)
    do cycle_number = 0, cycles
      if (cycle_number == 1) memory_before = resident_kb()
      call linear_solver_create(solver, rows, config)
      solution = 0
      call linear_solver_solve(solver, rhs, solution, status)
      call linear_solver_update_values(solver, rows)
      call linear_solver_solve(solver, rhs, solution, status)
      call linear_solver_destroy(solver)
    end do
    memory_after = resident_kb()
    if (is_root()) write(*, '(a,i0,a,i0,a,i0,a,i0,a)') 'N ', n, ', ', cycles, ' cycles: resident ', memory_before, &
        ' kB after the first, ', memory_after, ' kB after the last (rank 0)'
  end subroutine measure_leak

  integer function resident_kb()
    character(len=256) :: line
    integer :: unit, status
    resident_kb = -1
    open(newunit=unit, file='/proc/self/status', action='read', iostat=status)
    if (status /= 0) return
    do
      read(unit, '(a)', iostat=status) line
      if (status /= 0) exit
      if (line(1:6) == 'VmRSS:') read(line(7:), *) resident_kb
    end do
    close(unit)
  end function resident_kb

  !> Entries in [-1/2, 1/2) from a hash of the global row: the same b on any rank count.
  subroutine pseudo_random(rows, seed, values)
    type(sparse_rows_t), intent(in) :: rows
    integer, intent(in) :: seed
    real(wp), intent(out) :: values(:)
    integer :: r
    do r = 1, size(values)
      values(r) = modulo(sin(real(rows%first_row + r - 1, wp) * 12.9898_wp + seed * 78.233_wp) * 43758.5453_wp, &
                         1.0_wp) - 0.5_wp
    end do
  end subroutine pseudo_random

  subroutine start_clock(t)
    real(wp), intent(out) :: t
    call barrier()
    t = MPI_Wtime()
  end subroutine start_clock

  subroutine stop_clock(t)
    real(wp), intent(inout) :: t
    t = global_max(MPI_Wtime() - t)
  end subroutine stop_clock
end program bench_hypre
