!> Hydrodynamic loads on the immersed bodies by the paper's face sum (`&bodies load_method =
!> 'surface'`; Mark & van Wachem 2008; Anderson et al. 2025 Eqs. 8-10; docs/theory.md, "Surface
!> loads (face sum)"): F = sum_f (-p_f n_f + tau_f . n_f) A_f, T = sum_f r_f x (...) A_f, over the
!> faces of the body's icosphere (icosphere_mesh, 20 4^level faces; 320 the paper's).
!>
!> Quadrature (docs/theory.md, "Surface loads (face sum)"): face f of the icosphere is the flat triangle of the
!> affine image (a, b, b) of a unit-sphere triangle. Its point is the image of the unit-sphere
!> centroid direction, a point on the spheroid (the centroid projected to the surface along the
!> affine map); its normal the analytic one there; its weight the area of the spheroid patch over
!> the face: the solid angle of the unit-sphere triangle (Van Oosterom & Strackee 1983, IEEE Trans.
!> Biomed. Eng. 30, 125) times the area element of the affine map at the point,
!> |cof(S) m| = sqrt(b^4 m_1^2 + a^2 b^2 (m_2^2 + m_3^2)) for the unit direction m, S = diag(a, b, b),
!> the weights then rescaled to sum to the exact spheroid area (for a sphere they are exact already).
!>
!> Surface values from two probes along the normal, at P_k = B + k h n, h = probe_cells dx
!> (trilinear interpolation on each field's own grid, field_interpolation):
!> - pressure extrapolated linearly, p_B = 2 p_1 - p_2 (never dp/dn = 0, which misses the wall-normal
!>   pressure gradient mu lap(u).n, Mark & van Wachem 2008); the
!>   pressure probes use only the cells whose centre is outside every body (trilinear weights
!>   renormalised over them): the pressure inside a body has no meaning, and with the incremental
!>   scheme it drifts step after step at steady state (the re-imposition's cut-cell divergence is
!>   projected out again every step), which an unmasked probe one cell out picks up as a drift
!>   of the face sum (docs/studies/validation.md, "Surface loads and mesh geometry");
!> - viscous traction mu (grad u + grad u^T).n. Relative to the rigid motion, w = u - (U + Omega x r)
!>   vanishes on the surface, so its tangential derivatives vanish there: grad w = (dw/dn) n^T; with
!>   div w = 0 also n.dw/dn = 0, and the rigid part's rate of strain is zero, so
!>   (grad u + grad u^T).n = dw/dn on the surface, taken one-sided to second order,
!>   dw/dn = (4 w_1 - w_2) / (2 h) (w_B = 0).
!> Pressure time level: the loads are taken after the step's projection and re-imposition, with
!> u^{n+1} and the pressure the projection left, p^{n+1/2} (the incremental update p^{n-1/2} + rho phi,
!> or rho phi without it): the pressure that moved u^n to u^{n+1}, the step the momentum-balance
!> load also averages over.
!> The mean pressure gradient: the box is driven by a uniform force density f (N/m^3) standing for a
!> mean pressure gradient -grad P = f, and the periodic pressure p holds only the rest. The face sum
!> of the linear part P = -f.(x - c) is exact: -sum (P n A) -> f V (the divergence theorem; its
!> torque about the centroid vanishes), added analytically with the exact volume.
module immersed_surface_loads
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t, allocate_field, x_centre, y_centre, z_centre
  use periodic_box, only: minimum_image
  use field_interpolation, only: interpolate_at_points, on_x_faces, on_y_faces, on_z_faces, on_cell_centres
  use spheroid, only: spheroid_t, normal_at_point, surface_area, implicit_function
  use icosphere_mesh, only: icosphere_mesh_t, build_icosphere_mesh
  use quaternion, only: rotate_to_lab, rotate_to_body
  use vector_algebra, only: cross
  use error_handling, only: fatal
  use immersed_geometry, only: immersed_body_t
  implicit none
  private
  public :: surface_quadrature_t, surface_loads_t, surface_loads_create, surface_loads_compute

  !> The quadrature of one body's surface, body frame.
  type :: surface_quadrature_t
    integer :: n_points = 0
    real(wp), allocatable :: point(:, :)    !< (3, n) m, on the spheroid
    real(wp), allocatable :: normal(:, :)   !< (3, n) analytic outward unit normal
    real(wp), allocatable :: weight(:)      !< (n) m^2, sum = exact surface area
  end type surface_quadrature_t

  type :: surface_loads_t
    integer :: mesh_level = 2                     !< icosphere subdivisions (20 4^level faces)
    real(wp) :: probe_cells = 1.0_wp              !< h / dx (the prototype's best: 1)
    type(surface_quadrature_t), allocatable :: body(:)
    real(wp), allocatable :: fluid_cells(:, :, :)   !< 1 at the cell centres outside every body, else 0
    real(wp), allocatable :: marked_pose(:, :)      !< (7, n) centre and orientation fluid_cells was marked for
  end type surface_loads_t

contains

  !> The quadrature of every body (shapes in body order) at loads%mesh_level.
  subroutine surface_loads_create(loads, shapes)
    type(surface_loads_t), intent(inout) :: loads
    type(spheroid_t), intent(in) :: shapes(:)
    integer :: n
    if (.not. (loads%probe_cells >= 0.5_wp .and. loads%probe_cells <= 3.0_wp)) &
      call fatal('immersed surface loads: probe_cells outside 0.5 to 3 cells')
    if (allocated(loads%body)) deallocate(loads%body)
    allocate(loads%body(size(shapes)))
    do n = 1, size(shapes)
      call build_quadrature(shapes(n), loads%mesh_level, loads%body(n))
    end do
  end subroutine surface_loads_create

  subroutine build_quadrature(shape, level, quad)
    type(spheroid_t), intent(in) :: shape
    integer, intent(in) :: level
    type(surface_quadrature_t), intent(out) :: quad
    type(icosphere_mesh_t) :: mesh
    real(wp) :: corner(3, 3), direction(3), solid_angle, scale(3)
    integer :: f, k
    call build_icosphere_mesh(shape, level, mesh)
    quad%n_points = mesh%n_faces
    allocate(quad%point(3, mesh%n_faces), quad%normal(3, mesh%n_faces), quad%weight(mesh%n_faces))
    scale = [shape%a, shape%b, shape%b]
    do f = 1, mesh%n_faces
      do k = 1, 3
        corner(:, k) = mesh%vertices(:, mesh%faces(k, f)) / scale      ! back on the unit sphere
      end do
      direction = sum(corner, dim=2)
      direction = direction / norm2(direction)
      solid_angle = 2.0_wp * atan2(abs(dot_product(corner(:, 1), cross(corner(:, 2), corner(:, 3)))), &
                                   1.0_wp + dot_product(corner(:, 1), corner(:, 2)) + &
                                   dot_product(corner(:, 2), corner(:, 3)) + dot_product(corner(:, 3), corner(:, 1)))
      quad%point(:, f) = scale * direction
      quad%normal(:, f) = normal_at_point(shape, quad%point(:, f))
      quad%weight(f) = solid_angle * sqrt(shape%b**4 * direction(1)**2 + &
                                          (shape%a * shape%b)**2 * (direction(2)**2 + direction(3)**2))
    end do
    quad%weight = quad%weight * (surface_area(shape) / sum(quad%weight))
  end subroutine build_quadrature

  !> Force (N) and torque (N m, about each centre) on every body by the face sum (collective; every
  !> rank gets all loads). u, v, w, pressure with current halos; bodies placed at the time of u;
  !> velocity and angular_velocity their rigid motion; driving_force the mean pressure gradient's
  !> force density (N/m^3).
  subroutine surface_loads_compute(loads, grid, bodies, velocity, angular_velocity, u, v, w, pressure, viscosity, &
                                   density, driving_force, force, torque)
    type(surface_loads_t), intent(inout) :: loads
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    real(wp), intent(in) :: velocity(:, :), angular_velocity(:, :)
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:), pressure(0:, 0:, 0:)
    real(wp), intent(in) :: viscosity, density   !< m^2/s, kg/m^3 (mu = rho nu)
    real(wp), intent(in) :: driving_force(3)
    real(wp), intent(out) :: force(:, :), torque(:, :)
    real(wp), allocatable :: probes(:, :), normals(:, :), arms(:, :), values(:, :)
    real(wp) :: h, traction(3), relative(3, 2), p_surface
    integer :: n, f, total, m, k

    if (size(loads%body) /= size(bodies)) call fatal('immersed surface loads: quadrature and bodies differ in number')
    h = loads%probe_cells * max(grid%dx, grid%dy, grid%dz)
    total = sum(loads%body(:)%n_points)
    allocate(probes(3, 2 * total), normals(3, total), arms(3, total), values(2 * total, 4))
    m = 0
    do n = 1, size(bodies)
      do f = 1, loads%body(n)%n_points
        m = m + 1
        arms(:, m) = rotate_to_lab(bodies(n)%orientation, loads%body(n)%point(:, f))
        normals(:, m) = rotate_to_lab(bodies(n)%orientation, loads%body(n)%normal(:, f))
        probes(:, 2 * m - 1) = bodies(n)%centre + arms(:, m) + h * normals(:, m)
        probes(:, 2 * m) = bodies(n)%centre + arms(:, m) + 2.0_wp * h * normals(:, m)
      end do
    end do
    call interpolate_at_points(grid, u, on_x_faces, probes, values(:, 1))
    call interpolate_at_points(grid, v, on_y_faces, probes, values(:, 2))
    call interpolate_at_points(grid, w, on_z_faces, probes, values(:, 3))
    if (moved(loads%marked_pose, bodies)) call mark_fluid_cells(grid, bodies, loads%fluid_cells)
    call interpolate_at_points(grid, pressure, on_cell_centres, probes, values(:, 4), mask=loads%fluid_cells)

    m = 0
    do n = 1, size(bodies)
      force(:, n) = driving_force * bodies(n)%shape%volume
      torque(:, n) = 0
      do f = 1, loads%body(n)%n_points
        m = m + 1
        do k = 1, 2
          relative(:, k) = values(2 * m - 2 + k, 1:3) - &
                           (velocity(:, n) + cross(angular_velocity(:, n), arms(:, m) + k * h * normals(:, m)))
        end do
        p_surface = 2.0_wp * values(2 * m - 1, 4) - values(2 * m, 4)
        traction = -p_surface * normals(:, m) + density * viscosity * (4.0_wp * relative(:, 1) - relative(:, 2)) / (2.0_wp * h)
        force(:, n) = force(:, n) + loads%body(n)%weight(f) * traction
        torque(:, n) = torque(:, n) + loads%body(n)%weight(f) * cross(arms(:, m), traction)
      end do
    end do
  end subroutine surface_loads_compute

  !> True (and the poses recorded) unless every body has the pose of the last marking.
  logical function moved(marked_pose, bodies)
    real(wp), allocatable, intent(inout) :: marked_pose(:, :)
    type(immersed_body_t), intent(in) :: bodies(:)
    integer :: n
    moved = .not. allocated(marked_pose)
    if (.not. moved) moved = size(marked_pose, 2) /= size(bodies)
    if (moved) then
      if (allocated(marked_pose)) deallocate(marked_pose)
      allocate(marked_pose(7, size(bodies)))
    end if
    do n = 1, size(bodies)
      if (.not. moved) moved = any(marked_pose(1:3, n) /= bodies(n)%centre) .or. &
                               any(marked_pose(4:7, n) /= bodies(n)%orientation)
      marked_pose(1:3, n) = bodies(n)%centre
      marked_pose(4:7, n) = bodies(n)%orientation
    end do
  end function moved

  !> fluid_cells = 1 at the cell centres outside every body, 0 inside (the analytic spheroid; with
  !> the mesh geometry the cells between mesh and spheroid count as inside), on this rank's planes
  !> and its two halo planes. Only the cells within each body's bounding sphere are tested.
  subroutine mark_fluid_cells(grid, bodies, fluid_cells)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    real(wp), allocatable, intent(inout) :: fluid_cells(:, :, :)
    real(wp) :: box(3), reach, x(3)
    integer :: n, i, j, k, ii, jj
    if (.not. allocated(fluid_cells)) call allocate_field(grid, fluid_cells)
    fluid_cells = 1
    box = [grid%lx, grid%ly, grid%lz]
    do n = 1, size(bodies)
      reach = max(bodies(n)%shape%a, bodies(n)%shape%b)
      do k = 0, grid%nz_local + 1
        x(3) = minimum_image(z_centre(grid, k) - bodies(n)%centre(3), box(3))
        if (abs(x(3)) > reach) cycle
        do jj = floor((bodies(n)%centre(2) - reach) / grid%dy), ceiling((bodies(n)%centre(2) + reach) / grid%dy) + 1
          j = modulo(jj - 1, grid%ny) + 1
          x(2) = minimum_image(y_centre(grid, j) - bodies(n)%centre(2), box(2))
          do ii = floor((bodies(n)%centre(1) - reach) / grid%dx), ceiling((bodies(n)%centre(1) + reach) / grid%dx) + 1
            i = modulo(ii - 1, grid%nx) + 1
            x(1) = minimum_image(x_centre(grid, i) - bodies(n)%centre(1), box(1))
            if (implicit_function(bodies(n)%shape, rotate_to_body(bodies(n)%orientation, x)) < 0.0_wp) &
              fluid_cells(i, j, k) = 0
          end do
        end do
      end do
    end do
  end subroutine mark_fluid_cells
end module immersed_surface_loads
