! checks: 14
!> A tilted plane wall through the ghost rows (the immersed-boundary validation ladder, rung 3;
!> docs/studies/validation.md): a linear shear profile u = gamma s(x) t, zero on the wall, s the signed
!> distance to the wall and t a tangent, must come out of the imposition unchanged, because the
!> pure mirror (u_G = 2 u_B - u_M, Mark & van Wachem 2008) and the image point at 1.5 cells are
!> exact for a linear field vanishing on a plane and trilinear interpolation reproduces it.
!>
!> The wall: slabs of thickness 6 dx with unit normal n = (1, 2, 2)/3 (|(1, 2, 2)| = 3, so the
!> slabs repeat every L/3 along n and the periodic box holds an exact array of them, gaps of
!> 10 dx), at rest, on a 48^3 grid. immersed_geometry classifies spheroids only (a large oblate
!> spheroid is not a plane), so this test classifies the slab's nodes itself (solid where the
!> distance along n into the slab is positive; ghost when a 6-neighbour is fluid) and builds the
!> ghost records, in immersed_geometry's layout, from the plane's exact closest points
!> B = G + d n, M = 2B - G (or B + 1.5 dx n); immersed_imposition then imposes them as it does for any
!> body. The field s is linear over every stencil (stencils reach at most 3.2 dx from the wall,
!> half a gap is 5 dx and half a slab 3 dx).
!> The ghost values start from zero; after the imposition every ghost node holds the profile and no
!> fluid node has changed, to 1e-12 of the velocity scale (the profile at mid-gap), both couplings,
!> once with the interior nodes at the body's velocity (0, as the code runs) and once with them
!> holding the profile's continuation and not listed: the results agree because no mirror or
!> image stencil of this wall holds an interior node (the count is printed).
program test_immersed_slab
  use, intrinsic :: iso_fortran_env, only: int8
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use immersed_geometry, only: immersed_body_t, node_position, node_fluid, node_ghost, &
                               node_interior
  use immersed_boundary, only: immersed_boundary_t, imposition_report_t
  use immersed_placement, only: ibm_set_bodies
  use immersed_imposition, only: ibm_impose
  use test_framework, only: test_start, test_finish, check, check_below
  implicit none
  integer, parameter :: n_cells = 48
  real(wp), parameter :: box = 1.0e-3_wp, normal(3) = [1.0_wp, 2.0_wp, 2.0_wp] / 3.0_wp
  real(wp), parameter :: tangent(3) = [2.0_wp, -1.0_wp, 0.0_wp] / sqrt(5.0_wp), shear = 1.0_wp   ! 1/s
  character(len=8), parameter :: couplings(2) = [character(len=8) :: 'implicit', 'explicit']
  type(fluid_grid_t) :: grid
  type(immersed_boundary_t) :: ibm
  type(immersed_body_t) :: dummy(1)
  type(imposition_report_t) :: report
  real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)
  real(wp) :: period, thickness, offset, dx, worst_fluid, worst_ghost, scale
  integer :: variant, trial, n_touched, n_ghosts
  logical :: with_interior
  character(len=240) :: text
  character(len=64) :: label

  call parallel_start()
  call test_start('immersed_slab')
  call grid_create(grid, n_cells, n_cells, n_cells, box, box, box)
  dx = grid%dx
  period = box / 3.0_wp
  thickness = 6.0_wp * dx
  offset = 0.37_wp * dx          ! the wall at a sub-cell position
  call allocate_field(grid, u); call allocate_field(grid, v); call allocate_field(grid, w)
  scale = shear * 5.0_wp * dx    ! |u| at mid-gap

  do trial = 1, 2
    do variant = 1, 2
      with_interior = variant == 2
      ! A small sphere at rest sets up the imposition's arrays; its geometry is then replaced.
      ibm = immersed_boundary_t()
      ibm%settings%coupling = couplings(trial)
      dummy(1)%shape = make_spheroid('sphere', 3.0_wp * dx, 1000.0_wp)
      dummy(1)%centre = 0.5_wp * box
      call ibm_set_bodies(ibm, grid, dummy, reshape([0.0_wp, 0.0_wp, 0.0_wp], [3, 1]), &
                          reshape([0.0_wp, 0.0_wp, 0.0_wp], [3, 1]), classify=.true.)
      call build_slab(ibm, with_interior, couplings(trial) == 'explicit')
      call fill(1, u); call fill(2, v); call fill(3, w)
      call zero_ghosts(ibm)
      call ibm_impose(ibm, grid, u, v, w, report)
      call compare(ibm, worst_fluid, worst_ghost, n_touched, n_ghosts)
      label = trim(couplings(trial))//trim(merge('_interior_at_body_velocity', '_interior_linear          ', &
                                                 with_interior))
      write(text, '(a,a,i0,a,i0,a,es9.2,a,es9.2,a,i0)') trim(label), ': ghosts ', n_ghosts, &
          ', stencils holding an interior node ', n_touched, '; largest error / scale: fluid nodes ', worst_fluid, &
          ', ghost nodes ', worst_ghost, ', sweeps ', report%sweeps
      print '(a)', trim(text)
      call check(n_ghosts > 1000, trim(label)//'_slab_has_ghost_rows')
      call check_below(worst_ghost, 1.0e-12_wp, trim(label)//'_tilted_wall_shear_profile_exact_at_ghosts')
      call check_below(worst_fluid, 1.0e-12_wp, trim(label)//'_fluid_nodes_unchanged')
      if (trial == 1) call check(report%sweeps > 1, trim(label)//'_ghost_rows_solved_from_zero')
    end do
  end do
  call test_finish()

contains

  !> Depth of x into the slab measured from the wall at eta = 0: eta in [0, period).
  pure real(wp) function eta_of(x)
    real(wp), intent(in) :: x(3)
    eta_of = modulo(dot_product(normal, x) - offset, period)
  end function eta_of

  !> Signed distance to the nearest wall (negative inside the slab).
  pure real(wp) function signed_distance(x)
    real(wp), intent(in) :: x(3)
    real(wp) :: eta
    eta = eta_of(x)
    if (eta < thickness) then
      signed_distance = -min(eta, thickness - eta)
    else
      signed_distance = min(eta - thickness, period - eta)
    end if
  end function signed_distance

  !> The shear profile gamma s(x) t, component c, at every node (halos included: it is periodic).
  subroutine fill(c, field)
    integer, intent(in) :: c
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: i, j, k
    do k = 0, grid%nz_local + 1
      do j = 0, grid%ny + 1
        do i = 0, grid%nx + 1
          field(i, j, k) = shear * tangent(c) * signed_distance(node_position(grid, c, i, j, k))
        end do
      end do
    end do
  end subroutine fill

  !> Classification and ghost records of the slab for the three components.
  subroutine build_slab(ibm, with_interior, image)
    type(immersed_boundary_t), intent(inout) :: ibm
    logical, intent(in) :: with_interior, image
    integer(int8), allocatable :: status(:, :, :)
    integer, allocatable :: index_of(:, :, :)
    integer :: c, i, j, k, n, g, corner, bits(3), node(3)
    real(wp) :: x(3), eta, depth, outward(3), fraction(3), t(3), image_distance
    logical :: solid_neighbour_fluid
    allocate(status(n_cells, n_cells, n_cells), index_of(n_cells, n_cells, n_cells))
    do c = 1, 3
      associate (nodes => ibm%geometry%component(c))
        status = node_fluid
        do k = 1, n_cells
          do j = 1, n_cells
            do i = 1, n_cells
              if (eta_of(node_position(grid, c, i, j, k)) < thickness) status(i, j, k) = node_interior
            end do
          end do
        end do
        do k = 1, n_cells
          do j = 1, n_cells
            do i = 1, n_cells
              if (status(i, j, k) == node_fluid) cycle
              solid_neighbour_fluid = status(wrap(i - 1), j, k) == node_fluid .or. &
                  status(wrap(i + 1), j, k) == node_fluid .or. status(i, wrap(j - 1), k) == node_fluid .or. &
                  status(i, wrap(j + 1), k) == node_fluid .or. status(i, j, wrap(k - 1)) == node_fluid .or. &
                  status(i, j, wrap(k + 1)) == node_fluid
              if (solid_neighbour_fluid) status(i, j, k) = node_ghost
            end do
          end do
        end do
        ! Lists in storage order.
        nodes%n_ghost = count(status == node_ghost)
        nodes%n_interior = 0
        if (with_interior) nodes%n_interior = count(status == node_interior)
        if (allocated(nodes%ghost)) deallocate(nodes%ghost, nodes%interior, nodes%interior_body)
        allocate(nodes%ghost(nodes%n_ghost), nodes%interior(3, nodes%n_interior), nodes%interior_body(nodes%n_interior))
        nodes%interior_body = 1
        index_of = 0
        g = 0
        n = 0
        do k = 1, n_cells
          do j = 1, n_cells
            do i = 1, n_cells
              if (status(i, j, k) == node_ghost) then
                g = g + 1
                nodes%ghost(g)%node = [i, j, k]
                nodes%ghost(g)%body = 1
                index_of(i, j, k) = g
              else if (status(i, j, k) == node_interior .and. with_interior) then
                n = n + 1
                nodes%interior(:, n) = [i, j, k]
              end if
            end do
          end do
        end do
        do g = 1, nodes%n_ghost
          associate (ghost => nodes%ghost(g))
            x = node_position(grid, c, ghost%node(1), ghost%node(2), ghost%node(3))
            eta = eta_of(x)
            ! The nearer face: eta = 0 (outward normal -n) or eta = thickness (+n).
            if (eta < thickness - eta) then
              depth = eta
              outward = -normal
            else
              depth = thickness - eta
              outward = normal
            end if
            ghost%position = x
            ghost%normal = outward
            ghost%distance = depth
            ghost%surface_point = x + depth * outward
            image_distance = depth
            if (image) image_distance = max(depth, 1.5_wp * dx)
            ghost%image_distance = image_distance
            ghost%image_point = ghost%surface_point + image_distance * outward
            ghost%extrapolation = depth / image_distance
            fraction = real(ghost%node, wp) + (ghost%image_point - ghost%position) / dx
            ghost%lower_offset = floor(fraction) - ghost%node
            t = fraction - floor(fraction)
            ghost%self_corner = 0
            do corner = 1, 8
              bits = [mod(corner - 1, 2), mod((corner - 1) / 2, 2), (corner - 1) / 4]
              node = ghost%node + ghost%lower_offset + bits
              ghost%weight(corner) = product(merge(t, 1.0_wp - t, bits == 1))
              ghost%stencil(:, corner) = wrap(node)
              ghost%stencil_status(corner) = status(wrap(node(1)), wrap(node(2)), wrap(node(3)))
              ghost%stencil_local(corner) = node(3) >= 1 .and. node(3) <= n_cells
              ghost%stencil_ghost(corner) = 0
              if (ghost%stencil_local(corner) .and. ghost%stencil_status(corner) == node_ghost) &
                ghost%stencil_ghost(corner) = index_of(wrap(node(1)), wrap(node(2)), node(3))
              if (all(bits + ghost%lower_offset == 0)) ghost%self_corner = corner
            end do
          end associate
        end do
        ! Lever arms: the slab is at rest, so only their sizes matter.
        if (allocated(ibm%arms(c)%interior)) deallocate(ibm%arms(c)%interior, ibm%arms(c)%ghost, ibm%arms(c)%surface)
        allocate(ibm%arms(c)%interior(3, nodes%n_interior), ibm%arms(c)%ghost(3, nodes%n_ghost), &
                 ibm%arms(c)%surface(3, nodes%n_ghost))
        ibm%arms(c)%interior = 0; ibm%arms(c)%ghost = 0; ibm%arms(c)%surface = 0
      end associate
    end do
    ! Stencils reach at most 3 planes beyond a node; on one rank every stencil node beyond the
    ! slab is a periodic copy refreshed before each sweep.
    if (ibm%planes%halo_planes < 4) then
      ibm%planes%halo_planes = 4
      deallocate(ibm%planes%below, ibm%planes%above)
      allocate(ibm%planes%below(0:n_cells + 1, 0:n_cells + 1, -3:0, 3), ibm%planes%above(0:n_cells + 1, 0:n_cells + 1, &
               n_cells + 1:n_cells + 4, 3))
    end if
    ibm%planes%remote_ghosts = .true.
    ! Records edited by hand: counted as a classification (immersed_geometry_t%classifications).
    ibm%geometry%classifications = ibm%geometry%classifications + 1
  end subroutine build_slab

  !> Ghost values set to zero, so that the sweeps solve the ghost rows rather than confirm them.
  subroutine zero_ghosts(ibm)
    type(immersed_boundary_t), intent(in) :: ibm
    integer :: g
    do g = 1, ibm%geometry%component(1)%n_ghost
      associate (node => ibm%geometry%component(1)%ghost(g)%node)
        u(node(1), node(2), node(3)) = 0
      end associate
    end do
    do g = 1, ibm%geometry%component(2)%n_ghost
      associate (node => ibm%geometry%component(2)%ghost(g)%node)
        v(node(1), node(2), node(3)) = 0
      end associate
    end do
    do g = 1, ibm%geometry%component(3)%n_ghost
      associate (node => ibm%geometry%component(3)%ghost(g)%node)
        w(node(1), node(2), node(3)) = 0
      end associate
    end do
  end subroutine zero_ghosts

  !> Largest error against the profile over the fluid nodes and over the ghost nodes (relative to
  !> the scale), and the ghosts whose stencil holds an interior node.
  subroutine compare(ibm, worst_fluid, worst_ghost, n_touched, n_ghosts)
    type(immersed_boundary_t), intent(in) :: ibm
    real(wp), intent(out) :: worst_fluid, worst_ghost
    integer, intent(out) :: n_touched, n_ghosts
    integer :: c, g, i, j, k
    real(wp) :: error, s(3)
    worst_fluid = 0; worst_ghost = 0; n_touched = 0; n_ghosts = 0
    do k = 1, n_cells
      do j = 1, n_cells
        do i = 1, n_cells
          s = [signed_distance(node_position(grid, 1, i, j, k)), signed_distance(node_position(grid, 2, i, j, k)), &
               signed_distance(node_position(grid, 3, i, j, k))]
          if (s(1) > 0) worst_fluid = max(worst_fluid, abs(u(i, j, k) - shear * tangent(1) * s(1)))
          if (s(2) > 0) worst_fluid = max(worst_fluid, abs(v(i, j, k) - shear * tangent(2) * s(2)))
          if (s(3) > 0) worst_fluid = max(worst_fluid, abs(w(i, j, k) - shear * tangent(3) * s(3)))
        end do
      end do
    end do
    worst_fluid = worst_fluid / scale
    do c = 1, 3
      associate (nodes => ibm%geometry%component(c))
        n_ghosts = n_ghosts + nodes%n_ghost
        do g = 1, nodes%n_ghost
          associate (ghost => nodes%ghost(g))
            select case (c)
            case (1)
              error = u(ghost%node(1), ghost%node(2), ghost%node(3))
            case (2)
              error = v(ghost%node(1), ghost%node(2), ghost%node(3))
            case default
              error = w(ghost%node(1), ghost%node(2), ghost%node(3))
            end select
            worst_ghost = max(worst_ghost, abs(error - shear * tangent(c) * signed_distance(ghost%position)) / scale)
            if (any(ghost%stencil_status == node_interior)) n_touched = n_touched + 1
          end associate
        end do
      end associate
    end do
  end subroutine compare

  elemental integer function wrap(i)
    integer, intent(in) :: i
    wrap = modulo(i - 1, n_cells) + 1
  end function wrap
end program test_immersed_slab
