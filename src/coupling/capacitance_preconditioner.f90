!> A sparse approximation of the capacitance matrix C = A_G H^{-1} P_G^T (immersed_capacitance),
!> solved approximately as the preconditioner of the reduced system's GMRES.
!>
!> H = I - alpha L_h on the periodic grid is translation invariant, so H^{-1} P_G^T z is the
!> superposition of one discrete Green's function g = H^{-1} e_0 placed at the ghost nodes, and
!>     C_{GH} = sum_{a in S(G)} A_{Ga} g(x_a - x_H),
!> S(G) the nodes of G's row that are not interior (G itself and its image point's trilinear
!> corners). g decays geometrically away from its centre (by a factor of about 0.23 per cell at
!> nu dt/dx^2 = 0.4, the root of the one-dimensional recurrence), so keeping the offsets within a
!> window of a few cells in each direction gives a sparse matrix C~ close to C, with no FFT:
!> g itself costs one FFT Helmholtz solve whenever alpha changes (once per run at a fixed dt). The
!> capacitance-matrix idea of Buzbee, Dorr, George & Golub (1971, SIAM J. Numer. Anal. 8, 722)
!> with C formed explicitly, here truncated. Each rank holds the rows of its ghost nodes; their
!> columns include the neighbouring slabs' ghost nodes within the window (their nodes exchanged
!> once per assembly, their values once per product), so C~ does not depend on the rank count
!> (unless a slab is thinner than the window, which then narrows in z) and bodies across a slab
!> boundary keep their couplings. Its system is solved by a few GMRES
!> iterations (collective) with C~'s diagonal as right preconditioner.
!> The outer GMRES is flexible (the inner solve is not a fixed linear map), and its stopping rule
!> is on the true residual: the preconditioner changes the iterations, not the answer.
module capacitance_preconditioner
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM, MPI_MIN, MPI_INTEGER, MPI_Request, MPI_Irecv, MPI_Isend, &
                     MPI_Waitall, MPI_STATUSES_IGNORE
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp
  use fluid_grid, only: fluid_grid_t
  use immersed_nodes, only: component_nodes_t, node_interior, ghost_row_diagonal
  use hypre_fft_preconditioner, only: fft_helmholtz_preconditioner_t
  use gmres_cycle, only: gmres_cycle_t, gmres_prepare, gmres_begin, gmres_orthogonalise, gmres_coefficients
  implicit none
  private
  public :: local_capacitance_t, local_capacitance_green, local_capacitance_assemble, local_capacitance_solve
  public :: extended_plane

  integer, parameter :: tag_down = 450, tag_up = 460   !< messages to the rank below / above

  !> The window: at most 4 cells each way (the matrix's cost grows as its cube; at nu dt/dx^2 = 0.4
  !> the reduced solve takes 2 iterations with 4 cells, 2-3 with 3, 3 with 2:
  !> docs/studies/performance.md, "The local capacitance preconditioner"),
  !> and no wider than g needs: the offsets along an axis beyond it hold less than 1e-4 of g(0).
  integer, parameter :: largest_window = 4
  real(wp), parameter :: window_cutoff = 1.0e-4_wp

  type :: local_capacitance_t
    integer :: inner_iterations = 40            !< GMRES iterations of one application at most
    real(wp) :: inner_tolerance = 1.0e-6_wp     !< relative residual of one application
    real(wp) :: alpha = -1                      !< the coefficient g was computed for
    integer :: reach(3) = 0                     !< the window: offsets kept per direction (cells)
    real(wp), allocatable :: green(:, :, :)     !< g(dx, dy, dz), |d_i| <= reach(i) at least
    !> global index j + d (j in 1..ny, |d| <= reach) wrapped into 1..ny (no modulo per entry)
    integer, allocatable :: wrap_y(:)
    !> The columns: this rank's ghost nodes (1..n_local), then the neighbours' within reach(3)
    !> planes of the slab, from the rank below and from the rank above (more than one rank).
    integer :: n_local = 0, n_below = 0, n_above = 0
    integer, allocatable :: column_node(:, :)   !< (3, columns) i, j, k (k local, extended beyond the slab)
    integer, allocatable :: send_down(:), send_up(:)   !< this rank's ghosts within reach of its bottom / top
    real(wp), allocatable :: extended(:)        !< a vector over all columns (sparse_product)
    !> the columns by x-line (j, k), k from 1 - reach(3) to nz_local + reach(3):
    !> line_start(line) .. line_start(line + 1) - 1 index line_x (their i, ascending) and line_column
    integer, allocatable :: line_start(:), line_x(:), line_column(:)
    integer, allocatable :: row_start(:)        !< (n_ghost + 1) compressed rows of C~
    integer, allocatable :: column(:)
    real(wp), allocatable :: entry(:)
    real(wp), allocatable :: diagonal(:)        !< C~'s diagonal (the inner right preconditioner)
    real(wp), allocatable :: accumulated(:)     !< (columns) one row of C~ while it is summed
    integer, allocatable :: touched(:)          !< its columns so far
    logical, allocatable :: listed(:)           !< (columns) the column is in touched
    type(gmres_cycle_t) :: inner
    integer :: inner_total = 0                  !< inner iterations, summed (diagnostics)
  end type local_capacitance_t

contains

  !> g = H^{-1} e_0 near its centre, from one FFT Helmholtz solve (collective), and the window, when
  !> the coefficient of fft differs from the last one (the same on every rank: a restart
  !> recomputes the same g).
  subroutine local_capacitance_green(self, grid, fft, n_rows)
    type(local_capacitance_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    type(fft_helmholtz_preconditioner_t), intent(inout) :: fft
    integer, intent(in) :: n_rows
    real(wp), allocatable :: delta(:), image(:)
    integer :: extent(3), di, dj, dk, k, d, w, thinnest(1)
    if (allocated(self%green) .and. fft%coefficient == self%alpha) return
    ! One offset beyond the largest window (to choose the window below), and no offset that
    ! wraps onto another across the periodic box.
    extent = min(largest_window + 1, ([grid%nx, grid%ny, grid%nz] - 1) / 2)
    if (allocated(self%green)) deallocate(self%green)
    allocate(self%green(-extent(1):extent(1), -extent(2):extent(2), -extent(3):extent(3)))
    allocate(delta(n_rows), image(n_rows))
    delta = 0
    if (grid%z_offset == 0) delta(1) = 1     ! node (1, 1, 1)
    call fft%apply(delta, image)
    self%green = 0
    do dk = -extent(3), extent(3)
      k = modulo(dk, grid%nz) + 1 - grid%z_offset
      if (k < 1 .or. k > grid%nz_local) cycle
      do dj = -extent(2), extent(2)
        do di = -extent(1), extent(1)
          self%green(di, dj, dk) = image(modulo(di, grid%nx) + 1 + grid%nx * (modulo(dj, grid%ny) + grid%ny * (k - 1)))
        end do
      end do
    end do
    call MPI_Allreduce(MPI_IN_PLACE, self%green, size(self%green), mpi_wp, MPI_SUM, world)
    self%alpha = fft%coefficient
    ! The window per direction: the smallest that leaves out no axis offset where g exceeds
    ! window_cutoff g(0) (g decays slowest along the axes), at most largest_window.
    do d = 1, 3
      self%reach(d) = min(largest_window, extent(d))
      do w = 1, min(largest_window, extent(d) - 1)
        if (axis_value(d, w + 1) <= window_cutoff * self%green(0, 0, 0)) then
          self%reach(d) = w
          exit
        end if
      end do
    end do
    ! More than one rank: the planes in reach beyond a slab must be the adjacent slabs' (no slab
    ! thinner than the window), and those below and above distinct planes.
    if (grid%nz_local < grid%nz) then
      thinnest(1) = min(grid%nz_local, (grid%nz - grid%nz_local) / 2)
      call MPI_Allreduce(MPI_IN_PLACE, thinnest, 1, MPI_INTEGER, MPI_MIN, world)
      self%reach(3) = max(0, min(self%reach(3), thinnest(1)))
    end if
    call wrapped(grid%ny, self%reach(2), self%wrap_y)
  contains
    real(wp) function axis_value(direction, offset)
      integer, intent(in) :: direction, offset
      integer :: at(3)
      at = 0
      at(direction) = offset
      axis_value = abs(self%green(at(1), at(2), at(3)))
    end function axis_value

    subroutine wrapped(n, reach, table)
      integer, intent(in) :: n, reach
      integer, allocatable, intent(inout) :: table(:)
      integer :: i
      if (allocated(table)) deallocate(table)
      allocate(table(1 - reach:n + reach))
      table = [(modulo(i - 1, n) + 1, i = 1 - reach, n + reach)]
    end subroutine wrapped
  end subroutine local_capacitance_green

  !> C~'s rows of this rank's ghost nodes (collective: the neighbours' ghost nodes within the
  !> window are exchanged).
  subroutine local_capacitance_assemble(self, grid, nodes)
    type(local_capacitance_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: nodes
    integer :: g, corner, position, n_touched, n_entries, capacity
    real(wp) :: coefficient
    integer :: node(3)

    call gather_columns(self, grid, nodes)
    call sort_into_lines(self, grid)
    n_entries = 0
    self%accumulated = 0
    self%listed = .false.
    do g = 1, nodes%n_ghost
      n_touched = 0
      associate (ghost => nodes%ghost(g))
        ! The ghost node itself (the row's diagonal coefficient 1 + kappa w_G), then the other corners.
        node = [ghost%node(1), ghost%node(2), ghost%node(3) + grid%z_offset]
        call add_term(node, ghost_row_diagonal(ghost))
        do corner = 1, 8
          if (corner == ghost%self_corner .or. ghost%stencil_status(corner) == node_interior) cycle
          coefficient = ghost%extrapolation * ghost%weight(corner)
          if (coefficient == 0.0_wp) cycle
          call add_term(ghost%stencil(:, corner), coefficient)
        end do
      end associate
      capacity = size(self%column)
      if (n_entries + n_touched > capacity) call grow(self, max(2 * capacity, n_entries + n_touched))
      self%column(n_entries + 1:n_entries + n_touched) = self%touched(1:n_touched)
      self%entry(n_entries + 1:n_entries + n_touched) = self%accumulated(self%touched(1:n_touched))
      self%accumulated(self%touched(1:n_touched)) = 0
      self%listed(self%touched(1:n_touched)) = .false.
      n_entries = n_entries + n_touched
      self%row_start(g + 1) = n_entries + 1
      self%diagonal(g) = 0
      do position = self%row_start(g), n_entries
        if (self%column(position) == g) self%diagonal(g) = self%entry(position)
      end do
      if (.not. (abs(self%diagonal(g)) > 0.0_wp)) self%diagonal(g) = 1.0_wp
    end do
  contains
    !> coefficient * g(x_a - x_H) into the row for every column H within the window of node a
    !> (global i, j, k): the x-lines of the window, and along each the nodes within reach of a
    !> (the window's x-range split where it wraps across the box).
    subroutine add_term(a, coefficient)
      integer, intent(in) :: a(3)
      real(wp), intent(in) :: coefficient
      integer :: dj, dk, k, line, lowest, highest
      lowest = a(1) - self%reach(1)
      highest = a(1) + self%reach(1)
      do dk = -self%reach(3), self%reach(3)
        k = extended_plane(grid, self%reach(3), a(3) + dk)
        if (k < 1 - self%reach(3) .or. k > grid%nz_local + self%reach(3)) cycle
        do dj = -self%reach(2), self%reach(2)
          line = line_index(grid, self%reach(3), self%wrap_y(a(2) + dj), k)
          if (self%line_start(line) == self%line_start(line + 1)) cycle
          if (lowest < 1) then
            call add_along_line(a, coefficient, line, -dj, -dk, lowest + grid%nx, grid%nx)
            call add_along_line(a, coefficient, line, -dj, -dk, 1, highest)
          else if (highest > grid%nx) then
            call add_along_line(a, coefficient, line, -dj, -dk, lowest, grid%nx)
            call add_along_line(a, coefficient, line, -dj, -dk, 1, highest - grid%nx)
          else
            call add_along_line(a, coefficient, line, -dj, -dk, lowest, highest)
          end if
        end do
      end do
    end subroutine add_term

    !> The columns of x-line `line` with first <= i <= last (x_a - x_H = (-di, back_y, back_z)).
    subroutine add_along_line(a, coefficient, line, back_y, back_z, first, last)
      integer, intent(in) :: a(3), line, back_y, back_z, first, last
      real(wp), intent(in) :: coefficient
      integer :: position, low, high, h, di
      ! the first position with line_x >= first (bisection; the lines are short)
      low = self%line_start(line)
      high = self%line_start(line + 1)
      do while (low < high)
        position = (low + high) / 2
        if (self%line_x(position) < first) then
          low = position + 1
        else
          high = position
        end if
      end do
      do position = low, self%line_start(line + 1) - 1
        if (self%line_x(position) > last) exit
        h = self%line_column(position)
        di = modulo(self%line_x(position) - a(1) + self%reach(1), grid%nx) - self%reach(1)
        if (.not. self%listed(h)) then
          n_touched = n_touched + 1
          self%touched(n_touched) = h
          self%listed(h) = .true.
        end if
        ! g is even in each direction; the signs as in the formula
        self%accumulated(h) = self%accumulated(h) + coefficient * self%green(-di, back_y, back_z)
      end do
    end subroutine add_along_line
  end subroutine local_capacitance_assemble

  !> The plane of global index k (any integer, periodic) in this slab's extended local numbering:
  !> 1..nz_local in the slab, below 1 / above nz_local for the planes just beyond it (out of
  !> 1 - reach .. nz_local + reach when neither).
  pure integer function extended_plane(grid, reach, k_global)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: reach, k_global
    extended_plane = modulo(k_global - 1, grid%nz) + 1 - grid%z_offset
    if (extended_plane < 1 - reach) extended_plane = extended_plane + grid%nz
    if (extended_plane > grid%nz_local + reach) extended_plane = extended_plane - grid%nz
  end function extended_plane

  pure integer function line_index(grid, reach, j, k_extended)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: reach, j, k_extended
    line_index = j + grid%ny * (k_extended + reach - 1)
  end function line_index

  !> The columns: this rank's ghost nodes, then those of the neighbouring slabs within reach(3)
  !> planes (collective with the neighbours; one rank: none, the window wraps onto its own slab).
  subroutine gather_columns(self, grid, nodes)
    type(local_capacitance_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: nodes
    integer, allocatable, asynchronous :: down_nodes(:, :), up_nodes(:, :), from_below(:, :), from_above(:, :)
    integer, asynchronous :: counts(2), sizes(2)   ! received (below, above) and sent (up, down)
    integer :: g, n_columns, c
    type(MPI_Request) :: requests(4)
    self%n_local = nodes%n_ghost
    self%n_below = 0
    self%n_above = 0
    self%send_down = pack([(g, g = 1, nodes%n_ghost)], [(nodes%ghost(g)%node(3) <= self%reach(3), g = 1, nodes%n_ghost)])
    self%send_up = pack([(g, g = 1, nodes%n_ghost)], &
                        [(nodes%ghost(g)%node(3) > grid%nz_local - self%reach(3), g = 1, nodes%n_ghost)])
    if (grid%nz_local < grid%nz) then
      ! the counts, then the nodes (i, j, global k)
      call MPI_Irecv(counts(1), 1, MPI_INTEGER, grid%slab%rank_below, tag_up, world, requests(1))
      call MPI_Irecv(counts(2), 1, MPI_INTEGER, grid%slab%rank_above, tag_down, world, requests(2))
      sizes = [size(self%send_up), size(self%send_down)]
      call MPI_Isend(sizes(1), 1, MPI_INTEGER, grid%slab%rank_above, tag_up, world, requests(3))
      call MPI_Isend(sizes(2), 1, MPI_INTEGER, grid%slab%rank_below, tag_down, world, requests(4))
      call MPI_Waitall(4, requests, MPI_STATUSES_IGNORE)
      self%n_below = counts(1)
      self%n_above = counts(2)
      down_nodes = global_nodes(self%send_down)
      up_nodes = global_nodes(self%send_up)
      allocate(from_below(3, self%n_below), from_above(3, self%n_above))
      call MPI_Irecv(from_below, 3 * self%n_below, MPI_INTEGER, grid%slab%rank_below, tag_up, world, requests(1))
      call MPI_Irecv(from_above, 3 * self%n_above, MPI_INTEGER, grid%slab%rank_above, tag_down, world, requests(2))
      call MPI_Isend(up_nodes, 3 * size(self%send_up), MPI_INTEGER, grid%slab%rank_above, tag_up, world, requests(3))
      call MPI_Isend(down_nodes, 3 * size(self%send_down), MPI_INTEGER, grid%slab%rank_below, tag_down, world, &
                     requests(4))
      call MPI_Waitall(4, requests, MPI_STATUSES_IGNORE)
    end if
    n_columns = self%n_local + self%n_below + self%n_above
    call prepare(self, self%n_local, n_columns)
    do g = 1, self%n_local
      self%column_node(:, g) = nodes%ghost(g)%node
    end do
    do c = 1, self%n_below
      self%column_node(:, self%n_local + c) = [from_below(1:2, c), &
                                               extended_plane(grid, self%reach(3), from_below(3, c))]
    end do
    do c = 1, self%n_above
      self%column_node(:, self%n_local + self%n_below + c) = [from_above(1:2, c), &
                                                              extended_plane(grid, self%reach(3), from_above(3, c))]
    end do
  contains
    function global_nodes(ghosts) result(list)
      integer, intent(in) :: ghosts(:)
      integer :: list(3, size(ghosts)), n
      do n = 1, size(ghosts)
        list(:, n) = nodes%ghost(ghosts(n))%node + [0, 0, grid%z_offset]
      end do
    end function global_nodes
  end subroutine gather_columns

  !> y ~ C~^{-1} r on the ghost nodes (this rank's entries; collective): GMRES from y = 0 on
  !> C~ D^{-1} w = r, y = D^{-1} w, to inner_tolerance or inner_iterations.
  subroutine local_capacitance_solve(self, grid, r, y)
    type(local_capacitance_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: r(:)
    real(wp), intent(out) :: y(:)
    real(wp) :: norm(1), estimate, coefficients(self%inner_iterations)
    logical :: breakdown
    integer :: j
    y = 0
    norm(1) = sum(r**2)
    call MPI_Allreduce(MPI_IN_PLACE, norm, 1, mpi_wp, MPI_SUM, world)
    norm(1) = sqrt(norm(1))
    if (.not. (norm(1) > 0.0_wp)) return
    call gmres_prepare(self%inner, size(r), self%inner_iterations, collective=.true.)
    call gmres_begin(self%inner, r, norm(1))
    j = 0
    do while (j < self%inner_iterations)
      j = j + 1
      call sparse_product(self, grid, self%inner%basis(:, j) / self%diagonal, self%inner%basis(:, j + 1))
      call gmres_orthogonalise(self%inner, j, estimate, breakdown)
      if (breakdown) then
        j = j - 1
        exit
      end if
      if (estimate <= self%inner_tolerance * norm(1)) exit
    end do
    self%inner_total = self%inner_total + j
    if (j == 0) return
    call gmres_coefficients(self%inner, j, coefficients)
    y = matmul(self%inner%basis(:, 1:j), coefficients(1:j)) / self%diagonal
  end subroutine local_capacitance_solve

  !> The columns by x-line, ascending in i along each (a counting sort by line, then insertion
  !> along the short lines).
  subroutine sort_into_lines(self, grid)
    type(local_capacitance_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    integer, allocatable :: next(:), line_of(:)
    integer :: n_lines, n_columns, c, line, position, i
    n_lines = grid%ny * (grid%nz_local + 2 * self%reach(3))
    n_columns = size(self%column_node, 2)
    if (allocated(self%line_start)) then
      if (size(self%line_start) /= n_lines + 1) deallocate(self%line_start)
    end if
    if (.not. allocated(self%line_start)) allocate(self%line_start(n_lines + 1))
    if (allocated(self%line_x)) then
      if (size(self%line_x) /= n_columns) deallocate(self%line_x, self%line_column)
    end if
    if (.not. allocated(self%line_x)) allocate(self%line_x(n_columns), self%line_column(n_columns))
    line_of = [(line_index(grid, self%reach(3), self%column_node(2, c), self%column_node(3, c)), c = 1, n_columns)]
    ! counts in line_start(line + 1), then their prefix sums: the lines' first positions
    self%line_start = 0
    do c = 1, n_columns
      self%line_start(line_of(c) + 1) = self%line_start(line_of(c) + 1) + 1
    end do
    self%line_start(1) = 1
    do line = 1, n_lines
      self%line_start(line + 1) = self%line_start(line + 1) + self%line_start(line)
    end do
    next = self%line_start(1:n_lines)
    do c = 1, n_columns
      line = line_of(c)
      i = self%column_node(1, c)
      position = next(line)
      next(line) = position + 1
      do while (position > self%line_start(line))
        if (self%line_x(position - 1) <= i) exit
        self%line_x(position) = self%line_x(position - 1)
        self%line_column(position) = self%line_column(position - 1)
        position = position - 1
      end do
      self%line_x(position) = i
      self%line_column(position) = c
    end do
  end subroutine sort_into_lines

  !> C~ x on this rank's rows (collective: the neighbours' entries of x the rows reach are exchanged).
  subroutine sparse_product(self, grid, x, product)
    type(local_capacitance_t), intent(inout), asynchronous :: self
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: product(:)
    real(wp), allocatable, asynchronous :: down_values(:), up_values(:)
    type(MPI_Request) :: requests(4)
    integer :: g, first_above
    self%extended(1:self%n_local) = x
    if (grid%nz_local < grid%nz) then
      down_values = x(self%send_down)
      up_values = x(self%send_up)
      first_above = self%n_local + self%n_below + 1
      call MPI_Irecv(self%extended(self%n_local + 1:first_above - 1), self%n_below, mpi_wp, grid%slab%rank_below, &
                     tag_up, world, requests(1))
      call MPI_Irecv(self%extended(first_above:), self%n_above, mpi_wp, grid%slab%rank_above, tag_down, world, &
                     requests(2))
      call MPI_Isend(up_values, size(up_values), mpi_wp, grid%slab%rank_above, tag_up, world, requests(3))
      call MPI_Isend(down_values, size(down_values), mpi_wp, grid%slab%rank_below, tag_down, world, requests(4))
      call MPI_Waitall(4, requests, MPI_STATUSES_IGNORE)
    end if
    do g = 1, self%n_local
      product(g) = dot_product(self%entry(self%row_start(g):self%row_start(g + 1) - 1), &
                               self%extended(self%column(self%row_start(g):self%row_start(g + 1) - 1)))
    end do
  end subroutine sparse_product

  !> Storage for n_rows rows (this rank's ghost nodes) and n_columns columns.
  subroutine prepare(self, n_rows, n_columns)
    type(local_capacitance_t), intent(inout) :: self
    integer, intent(in) :: n_rows, n_columns
    if (allocated(self%diagonal)) then
      if (size(self%diagonal) /= n_rows) deallocate(self%diagonal, self%row_start)
    end if
    if (.not. allocated(self%diagonal)) allocate(self%diagonal(n_rows), self%row_start(n_rows + 1))
    if (allocated(self%accumulated)) then
      if (size(self%accumulated) /= n_columns) deallocate(self%accumulated, self%touched, self%listed, &
                                                          self%column_node, self%extended)
    end if
    if (.not. allocated(self%accumulated)) allocate(self%accumulated(n_columns), self%touched(n_columns), &
                                                    self%listed(n_columns), self%column_node(3, n_columns), &
                                                    self%extended(n_columns))
    if (.not. allocated(self%column)) allocate(self%column(max(1, 64 * n_rows)), self%entry(max(1, 64 * n_rows)))
    self%row_start(1) = 1
  end subroutine prepare

  subroutine grow(self, capacity)
    type(local_capacitance_t), intent(inout) :: self
    integer, intent(in) :: capacity
    integer, allocatable :: column(:)
    real(wp), allocatable :: entry(:)
    allocate(column(capacity), entry(capacity))
    column(1:size(self%column)) = self%column
    entry(1:size(self%entry)) = self%entry
    call move_alloc(column, self%column)
    call move_alloc(entry, self%entry)
  end subroutine grow
end module capacitance_preconditioner
