!> Closest point, outward normal and signed distance from a point to the triangulated spheroid
!> (icosphere_mesh), and the inside test: the immersed boundary's `&bodies geometry = 'mesh'`, the
!> paper's fidelity option (B = the closest point on the triangulated surface, Mark & van Wachem
!> 2008; docs/theory.md, "Immersed boundary geometry"). The sibling of spheroid_distance, which
!> gives the same for the analytic surface.
!>
!> The mesh is the affine image of a convex icosphere, so it is convex and is the intersection of
!> the half-spaces behind its faces: a point is inside when it lies strictly behind every face
!> plane. The closest point is the nearest of the closest points on the triangles (Ericson,
!> "Real-Time Collision Detection", 2005, section 5.1.5, by the Voronoi regions of the triangle),
!> a brute-force pass over the faces. The normal is the flat normal of the face that holds the
!> closest point (for a point inside, the closest point lies on the face whose plane is nearest);
!> for a point outside whose closest point is an edge or a vertex, the direction from it to the
!> point. Everything is in the body frame of icosphere_mesh; mesh_lab_closest_point rotates.
module mesh_distance
  use agglo_kinds, only: wp
  use icosphere_mesh, only: icosphere_mesh_t
  use quaternion, only: rotate_to_body, rotate_to_lab
  use spheroid_distance, only: surface_projection_t
  implicit none
  private
  public :: mesh_contains, mesh_body_closest_point, mesh_lab_closest_point, triangle_closest_point

contains

  !> True if p (body frame, m) lies strictly inside the mesh: behind every face plane.
  pure logical function mesh_contains(mesh, p)
    type(icosphere_mesh_t), intent(in) :: mesh
    real(wp), intent(in) :: p(3)
    integer :: f
    mesh_contains = .false.
    do f = 1, mesh%n_faces
      if (.not. (dot_product(p - mesh%face_centres(:, f), mesh%face_normals(:, f)) < 0.0_wp)) return
    end do
    mesh_contains = .true.
  end function mesh_contains

  !> The projection of p (body frame, m) onto the mesh: closest point, normal, signed distance
  !> (negative inside).
  pure function mesh_body_closest_point(mesh, p) result(projection)
    type(icosphere_mesh_t), intent(in) :: mesh
    real(wp), intent(in) :: p(3)
    type(surface_projection_t) :: projection
    real(wp) :: candidate(3), distance_squared, best
    integer :: f, nearest
    logical :: on_face_interior, best_interior
    best = huge(1.0_wp)
    nearest = 1
    best_interior = .true.
    do f = 1, mesh%n_faces
      call triangle_closest_point(p, mesh%vertices(:, mesh%faces(1, f)), mesh%vertices(:, mesh%faces(2, f)), &
                                  mesh%vertices(:, mesh%faces(3, f)), candidate, on_face_interior)
      distance_squared = sum((p - candidate)**2)
      if (distance_squared < best) then
        best = distance_squared
        nearest = f
        projection%point = candidate
        best_interior = on_face_interior
      end if
    end do
    projection%normal = mesh%face_normals(:, nearest)
    if (mesh_contains(mesh, p)) then
      projection%signed_distance = -sqrt(best)
    else
      projection%signed_distance = sqrt(best)
      ! Outside, nearest to an edge or a vertex: the normal of the surface there is the direction
      ! to the point (any face normal of the edge or vertex would do for a point on the surface).
      if (.not. best_interior .and. best > 0.0_wp) projection%normal = (p - projection%point) / sqrt(best)
    end if
  end function mesh_body_closest_point

  !> The same for a lab point x of the body with centre `centre` (the image wanted) and orientation
  !> q (body -> lab): point and normal in the lab frame.
  pure function mesh_lab_closest_point(mesh, centre, q, x) result(projection)
    type(icosphere_mesh_t), intent(in) :: mesh
    real(wp), intent(in) :: centre(3), q(4), x(3)
    type(surface_projection_t) :: projection
    projection = mesh_body_closest_point(mesh, rotate_to_body(q, x - centre))
    projection%point = centre + rotate_to_lab(q, projection%point)
    projection%normal = rotate_to_lab(q, projection%normal)
  end function mesh_lab_closest_point

  !> Closest point c of triangle (a, b, d) to p (Ericson 2005, ClosestPtPointTriangle: the Voronoi
  !> region of p among the vertices, the edges and the face); interior = it lies inside the face.
  pure subroutine triangle_closest_point(p, a, b, d, c, interior)
    real(wp), intent(in) :: p(3), a(3), b(3), d(3)
    real(wp), intent(out) :: c(3)
    logical, intent(out) :: interior
    real(wp) :: ab(3), ad(3), ap(3), bp(3), dp(3), d1, d2, d3, d4, d5, d6, va, vb, vd, v, w, denominator
    interior = .false.
    ab = b - a
    ad = d - a
    ap = p - a
    d1 = dot_product(ab, ap)
    d2 = dot_product(ad, ap)
    if (d1 <= 0.0_wp .and. d2 <= 0.0_wp) then
      c = a
      return
    end if
    bp = p - b
    d3 = dot_product(ab, bp)
    d4 = dot_product(ad, bp)
    if (d3 >= 0.0_wp .and. d4 <= d3) then
      c = b
      return
    end if
    vd = d1 * d4 - d3 * d2
    if (vd <= 0.0_wp .and. d1 >= 0.0_wp .and. d3 <= 0.0_wp) then
      c = a + (d1 / (d1 - d3)) * ab
      return
    end if
    dp = p - d
    d5 = dot_product(ab, dp)
    d6 = dot_product(ad, dp)
    if (d6 >= 0.0_wp .and. d5 <= d6) then
      c = d
      return
    end if
    vb = d5 * d2 - d1 * d6
    if (vb <= 0.0_wp .and. d2 >= 0.0_wp .and. d6 <= 0.0_wp) then
      c = a + (d2 / (d2 - d6)) * ad
      return
    end if
    va = d3 * d6 - d5 * d4
    if (va <= 0.0_wp .and. (d4 - d3) >= 0.0_wp .and. (d5 - d6) >= 0.0_wp) then
      c = b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (d - b)
      return
    end if
    denominator = 1.0_wp / (va + vb + vd)
    v = vb * denominator
    w = vd * denominator
    c = a + v * ab + w * ad
    interior = .true.
  end subroutine triangle_closest_point
end module mesh_distance
