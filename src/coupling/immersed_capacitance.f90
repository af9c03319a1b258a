!> The Crank-Nicolson predictor's system with the immersed-boundary rows, A u = b, solved on the
!> ghost rows only: a capacitance-matrix formulation (Buzbee, Dorr, George & Golub 1971, SIAM J.
!> Numer. Anal. 8, 722; Proskurowski & Widlund 1976) with flexible GMRES (Saad 1993; gmres_cycle)
!> on the reduced system, preconditioned by an approximate solve with a sparse approximation of
!> its matrix (capacitance_preconditioner) (docs/theory.md, "Linear solver (hypre)";
!> docs/studies/performance.md).
!>
!> A differs from the periodic Helmholtz operator H = I - alpha L_h (which the FFT inverts exactly)
!> only in the ghost rows G and the interior rows I. The fluid rows' 7-point stencils hold fluid and
!> ghost nodes only (a ghost node is a solid node with a fluid neighbour), so the interior values
!> enter the system only through the ghost rows' stencils, where they are known (u = u_rigid). For
!> any z on the ghost rows, u(z) = H^{-1} (b + P_G^T z) satisfies every fluid row exactly; the
!> solution of A u = b is u(z) with the interior values put in, for the z that makes the ghost rows
!> hold:   C z = r0,   C = A_G|_{F,G} H^{-1} P_G^T,   r0 = b_G - A_G u_mix(0)
!> (u_mix: the interior nodes at their rigid values). C has one row and column per ghost node;
!> applying it is one FFT Helmholtz solve and the ghost rows' stencils. Every outer cycle updates
!> u(z) from the images it kept (no further FFT solve) and checks the true residual of the whole
!> system: the fluid rows hold to the FFT's rounding and the interior rows exactly, so
!> ||b - A u|| = ||b_G - A_G u_mix|| and the stopping rule ||b - A u||_2 <= tolerance ||b||_2 is
!> hypre's (hypre_solver) on the same rows.
!> The first z comes from u^n (capacitance_first_guess; the checkpoint holds u^n, so a restart
!> continues bit for bit), else 0.
module immersed_capacitance
  use mpi_f08, only: MPI_Request, MPI_Irecv, MPI_Isend, MPI_Waitall, MPI_Allreduce, MPI_IN_PLACE, MPI_SUM, &
                     MPI_STATUSES_IGNORE
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp
  use fluid_grid, only: fluid_grid_t
  use immersed_nodes, only: component_nodes_t, ghost_row_diagonal
  use hypre_fft_preconditioner, only: fft_helmholtz_preconditioner_t
  use timer_registry, only: timer_tic, timer_toc
  use gmres_cycle, only: gmres_cycle_t, gmres_prepare, gmres_begin, gmres_orthogonalise, gmres_coefficients
  use capacitance_preconditioner, only: local_capacitance_t, local_capacitance_green, local_capacitance_assemble, &
                                        local_capacitance_solve, extended_plane
  implicit none
  private
  public :: capacitance_work_t, capacitance_result_t, capacitance_solve, capacitance_first_guess

  !> Work arrays of the reduced solve, kept between steps (no allocation per step at fixed sizes).
  type :: capacitance_work_t
    real(wp), allocatable :: forcing(:)                 !< rows: b + P^T z, or M v on the ghost rows
    real(wp), allocatable :: images(:, :)               !< (rows, j) H^{-1} P_G^T w_j of a cycle
    real(wp), allocatable :: below(:, :, :), above(:, :, :)   !< the neighbours' planes the stencils read
    real(wp), allocatable :: send_up(:), send_down(:)        !< this slab's top and bottom planes
    type(gmres_cycle_t) :: krylov                       !< the outer (flexible) GMRES cycle on the ghost rows
    real(wp), allocatable :: preconditioned(:, :)       !< (n_ghost, restart) w_j = P v_j of a cycle
    type(local_capacitance_t) :: preconditioner         !< P ~ C^{-1}
  end type capacitance_work_t

  type :: capacitance_result_t
    logical :: converged = .false.
    integer :: iterations = 0          !< GMRES iterations (one FFT solve each)
    integer :: inner_iterations = 0    !< GMRES iterations of the preconditioner's solves (no FFT)
    integer :: fft_solves = 0          !< all FFT Helmholtz solves (iterations + one per outer cycle)
    real(wp) :: relative_residual = huge(1.0_wp)   !< ||b - A u||_2 / ||b||_2, the true one
  end type capacitance_result_t

contains

  !> Solve A solution = rhs (collective). rhs: this rank's rows, with the ghost rows' and interior
  !> rows' right-hand sides in place (as for the whole system); ghost_rows, interior_rows: their
  !> local rows in nodes' order; halo: the planes beyond the slab the stencils reach (>= 1).
  !> z: on entry the first guess of the ghost forcing, on exit the converged one. fft: H^{-1}
  !> (an FFT Helmholtz solve without replaced rows).
  subroutine capacitance_solve(work, grid, nodes, ghost_rows, interior_rows, rhs, halo, stencils_leave_slab, fft, &
                               tolerance, max_iterations, restart, z, solution, result)
    type(capacitance_work_t), intent(inout) :: work
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: nodes
    integer, intent(in) :: ghost_rows(:), interior_rows(:)
    real(wp), intent(in) :: rhs(:)
    integer, intent(in) :: halo
    !> some ghost stencil (on some rank) reaches beyond its slab (the same on every rank): else the
    !> ghost rows need no planes from the neighbours and no exchange is made
    logical, intent(in) :: stencils_leave_slab
    type(fft_helmholtz_preconditioner_t), intent(inout) :: fft
    real(wp), intent(in) :: tolerance
    integer, intent(in) :: max_iterations, restart
    real(wp), intent(inout) :: z(:)
    real(wp), intent(out) :: solution(:)
    type(capacitance_result_t), intent(out) :: result
    real(wp) :: target_norm, residual_norm, estimate, norms(1)
    real(wp), allocatable :: residual(:), y(:)
    logical :: breakdown
    integer :: ng, m, j, inner_before

    ng = size(ghost_rows)
    m = max(1, min(restart, max_iterations))
    call prepare(work, grid, size(rhs), ng, m, halo)
    inner_before = work%preconditioner%inner_total
    call timer_tic('  capacitance matrix')
    call local_capacitance_green(work%preconditioner, grid, fft, size(rhs))
    call local_capacitance_assemble(work%preconditioner, grid, nodes)
    call timer_toc('  capacitance matrix')
    allocate(residual(ng), y(m))
    norms(1) = sum(rhs**2)
    call MPI_Allreduce(MPI_IN_PLACE, norms, 1, mpi_wp, MPI_SUM, world)
    target_norm = tolerance * sqrt(norms(1))

    ! u(z) for the first z: the one FFT solve of the right-hand side.
    work%forcing = rhs
    work%forcing(ghost_rows) = work%forcing(ghost_rows) + z
    call fft%apply(work%forcing, solution)
    result%fft_solves = 1
    solution(interior_rows) = rhs(interior_rows)
    ! From here on the forcing is 0 but on the ghost rows (each iteration writes all of them).
    work%forcing = 0
    do
      ! The true residual of the ghost rows (the whole system's, module header).
      call apply_ghost_rows(work, grid, nodes, halo, stencils_leave_slab, solution, residual)
      residual = rhs(ghost_rows) - residual
      residual_norm = global_norm(residual)
      result%relative_residual = residual_norm / max(sqrt(norms(1)), tiny(1.0_wp))
      if (residual_norm <= target_norm) then
        result%converged = .true.
        exit
      end if
      if (result%iterations >= max_iterations) exit

      ! One flexible GMRES cycle on C d = residual from d = 0, right-preconditioned by the local
      ! capacitance solve P ~ C^{-1} (capacitance_preconditioner): w_j = P v_j kept, its H^{-1}
      ! image with the interior values held at 0, the ghost rows' stencils; then z = z + W y and
      ! u = u + (images) y (no further FFT solve).
      call gmres_begin(work%krylov, residual, residual_norm)
      j = 0
      do while (j < m .and. result%iterations < max_iterations)
        j = j + 1
        result%iterations = result%iterations + 1
        call timer_tic('  capacitance solves')
        call local_capacitance_solve(work%preconditioner, grid, work%krylov%basis(:, j), work%preconditioned(:, j))
        call timer_toc('  capacitance solves')
        work%forcing(ghost_rows) = work%preconditioned(:, j)
        if (size(work%images, 2) < j) call grow_images(work, j)
        call fft%apply(work%forcing, work%images(:, j))
        result%fft_solves = result%fft_solves + 1
        work%images(interior_rows, j) = 0
        call apply_ghost_rows(work, grid, nodes, halo, stencils_leave_slab, work%images(:, j), work%krylov%basis(:, j + 1))
        call gmres_orthogonalise(work%krylov, j, estimate, breakdown)
        if (breakdown) then
          ! The Krylov space is invariant: solve with the columns so far; the outer loop checks the
          ! true residual.
          j = j - 1
          exit
        end if
        if (estimate <= target_norm) exit
      end do
      if (j == 0) exit
      call gmres_coefficients(work%krylov, j, y)
      z = z + matmul(work%preconditioned(:, 1:j), y(1:j))
      solution = solution + matmul(work%images(:, 1:j), y(1:j))
    end do
    result%inner_iterations = work%preconditioner%inner_total - inner_before
  end subroutine capacitance_solve

  !> Work arrays sized for this solve.
  subroutine prepare(work, grid, n_rows, ng, m, halo)
    type(capacitance_work_t), intent(inout) :: work
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: n_rows, ng, m, halo
    if (allocated(work%forcing)) then
      if (size(work%forcing) /= n_rows) deallocate(work%forcing)
    end if
    if (.not. allocated(work%forcing)) allocate(work%forcing(n_rows))
    if (allocated(work%images)) then
      if (size(work%images, 1) /= n_rows) deallocate(work%images)
    end if
    if (.not. allocated(work%images)) allocate(work%images(n_rows, 0))
    call prepare_planes(work, grid, halo)
    call gmres_prepare(work%krylov, ng, m, collective=.true.)
    if (allocated(work%preconditioned)) then
      if (any(shape(work%preconditioned) /= [ng, m])) deallocate(work%preconditioned)
    end if
    if (.not. allocated(work%preconditioned)) allocate(work%preconditioned(ng, m))
  end subroutine prepare

  !> Room for j images: the columns grow to what the cycles have needed (a few; the restart
  !> length at most), kept between solves.
  subroutine grow_images(work, j)
    type(capacitance_work_t), intent(inout) :: work
    integer, intent(in) :: j
    real(wp), allocatable :: grown(:, :)
    allocate(grown(size(work%images, 1), j))
    grown(:, 1:size(work%images, 2)) = work%images
    call move_alloc(grown, work%images)
  end subroutine grow_images

  subroutine prepare_planes(work, grid, halo)
    type(capacitance_work_t), intent(inout) :: work
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: halo
    if (allocated(work%below)) then
      if (size(work%below, 3) /= halo) deallocate(work%below, work%above, work%send_up, work%send_down)
    end if
    if (.not. allocated(work%below)) allocate(work%below(grid%nx, grid%ny, halo), work%above(grid%nx, grid%ny, halo), &
                                              work%send_up(grid%nx * grid%ny * halo), work%send_down(grid%nx * grid%ny * halo))
  end subroutine prepare_planes

  !> The planes beyond the slab that the stencils read, from the neighbouring ranks (collective;
  !> one rank: its own planes, periodically). The planes of a slab are contiguous blocks of its rows.
  subroutine exchange_rows_planes(work, grid, halo, values)
    type(capacitance_work_t), intent(inout), asynchronous :: work
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: halo
    real(wp), intent(in) :: values(:)
    integer :: plane, nzl
    type(MPI_Request) :: requests(4)
    plane = grid%nx * grid%ny
    nzl = grid%nz_local
    ! Both directions at once (one wait), from send buffers of the work (not sections of values).
    work%send_up = values(plane * (nzl - halo) + 1:plane * nzl)
    work%send_down = values(1:plane * halo)
    call MPI_Irecv(work%below, plane * halo, mpi_wp, grid%slab%rank_below, 430, world, requests(1))
    call MPI_Irecv(work%above, plane * halo, mpi_wp, grid%slab%rank_above, 440, world, requests(2))
    call MPI_Isend(work%send_up, plane * halo, mpi_wp, grid%slab%rank_above, 430, world, requests(3))
    call MPI_Isend(work%send_down, plane * halo, mpi_wp, grid%slab%rank_below, 440, world, requests(4))
    call MPI_Waitall(4, requests, MPI_STATUSES_IGNORE)
  end subroutine exchange_rows_planes

  !> The value at node (i, j global; k global, any integer, wrapped periodically) from this slab's
  !> rows or the copied planes (exchange_rows_planes).
  real(wp) function value_at(work, grid, halo, values, i, j, k_global)
    type(capacitance_work_t), intent(in) :: work
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: halo, i, j, k_global
    real(wp), intent(in) :: values(:)
    integer :: k
    k = extended_plane(grid, halo, k_global)
    if (k < 1) then
      value_at = work%below(i, j, k + halo)
    else if (k > grid%nz_local) then
      value_at = work%above(i, j, k - grid%nz_local)
    else
      value_at = values(i + grid%nx * ((j - 1) + grid%ny * (k - 1)))
    end if
  end function value_at

  !> The ghost rows applied to a vector of this rank's rows (collective):
  !> (A_G values)_g = (1 + kappa w_G) u_G + kappa sum_{corners /= G} w_c u_c.
  subroutine apply_ghost_rows(work, grid, nodes, halo, exchange, values, product)
    type(capacitance_work_t), intent(inout) :: work
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: nodes
    integer, intent(in) :: halo
    logical, intent(in) :: exchange   !< the stencils reach beyond the slab (on some rank)
    real(wp), intent(in) :: values(:)
    real(wp), intent(out) :: product(:)
    integer :: g, corner, row
    real(wp) :: total
    if (exchange) call exchange_rows_planes(work, grid, halo, values)
    do g = 1, nodes%n_ghost
      associate (ghost => nodes%ghost(g))
        row = ghost%node(1) + grid%nx * ((ghost%node(2) - 1) + grid%ny * (ghost%node(3) - 1))
        total = ghost_row_diagonal(ghost) * values(row)
        do corner = 1, 8
          if (corner == ghost%self_corner) cycle
          total = total + ghost%extrapolation * ghost%weight(corner) * &
                  value_at(work, grid, halo, values, ghost%stencil(1, corner), ghost%stencil(2, corner), &
                           ghost%stencil(3, corner))
        end do
        product(g) = total
      end associate
    end do
  end subroutine apply_ghost_rows

  !> The first guess of the ghost forcing from a field close to the solution (u^n): z_g =
  !> ((I - alpha L_h) u)_G - b_G, the forcing that would make H^{-1}(b + P^T z) take u's values
  !> near the ghost node G (collective). values: this rank's rows of u, the interior nodes at their
  !> rigid values.
  subroutine capacitance_first_guess(work, grid, nodes, halo, alpha, values, rhs_ghost, z)
    type(capacitance_work_t), intent(inout) :: work
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: nodes
    integer, intent(in) :: halo
    real(wp), intent(in) :: alpha
    real(wp), intent(in) :: values(:), rhs_ghost(:)
    real(wp), intent(out) :: z(:)
    call prepare_planes(work, grid, halo)
    call helmholtz_at_ghosts(work, grid, nodes, halo, alpha, values, z)
    z = z - rhs_ghost
  end subroutine capacitance_first_guess

  !> ((I - alpha L_h) values) at the ghost nodes (collective).
  subroutine helmholtz_at_ghosts(work, grid, nodes, halo, alpha, values, product)
    type(capacitance_work_t), intent(inout) :: work
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: nodes
    integer, intent(in) :: halo
    real(wp), intent(in) :: alpha
    real(wp), intent(in) :: values(:)
    real(wp), intent(out) :: product(:)
    real(wp) :: cx, cy, cz
    integer :: g, i, j, k, kg, row
    call exchange_rows_planes(work, grid, halo, values)
    cx = alpha / grid%dx**2
    cy = alpha / grid%dy**2
    cz = alpha / grid%dz**2
    do g = 1, nodes%n_ghost
      i = nodes%ghost(g)%node(1)
      j = nodes%ghost(g)%node(2)
      k = nodes%ghost(g)%node(3)
      kg = k + grid%z_offset
      row = i + grid%nx * ((j - 1) + grid%ny * (k - 1))
      product(g) = (1.0_wp + 2.0_wp * (cx + cy + cz)) * values(row) &
                   - cx * (value_at(work, grid, halo, values, modulo(i - 2, grid%nx) + 1, j, kg) &
                           + value_at(work, grid, halo, values, modulo(i, grid%nx) + 1, j, kg)) &
                   - cy * (value_at(work, grid, halo, values, i, modulo(j - 2, grid%ny) + 1, kg) &
                           + value_at(work, grid, halo, values, i, modulo(j, grid%ny) + 1, kg)) &
                   - cz * (value_at(work, grid, halo, values, i, j, kg - 1) + value_at(work, grid, halo, values, i, j, kg + 1))
    end do
  end subroutine helmholtz_at_ghosts

  real(wp) function global_norm(vector)
    real(wp), intent(in) :: vector(:)
    real(wp) :: total(1)
    total(1) = sum(vector**2)
    call MPI_Allreduce(MPI_IN_PLACE, total, 1, mpi_wp, MPI_SUM, world)
    global_norm = sqrt(total(1))
  end function global_norm
end module immersed_capacitance
