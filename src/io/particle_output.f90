!> Per-run particle outputs: particles.h5 (time series and events table) and summary.json.
!> The file is written by rank 0 alone through a serial HDF5 handle; every routine may be called on
!> every rank (the others return at once), so a driver needs no rank tests.
!>
!> Two layers:
!>  - generic, by named columns: stage the values of one row with sample_value(out, name, value)
!>    (value: real(wp) scalar -> dataset (N), or real(wp) vector of width m -> dataset (m, N) in
!>    Fortran = (N, m) in h5py) and commit it with sample_end(out, ...); the same for the events table
!>    with event_value / event_end (columns under /events). The first row fixes the columns of a table;
!>    every later row must set exactly those (anything else is a programming error and stops the run).
!>  - the particle layout of docs/outputs.md: append_particles_sample(out, time, particles, pairs) for
!>    N bodies and their pairs (append_pair_sample for one pair) and append_collision_event(out, event),
!>    with the record types below.
!> Rows are buffered in memory (buffer_rows of them, fewer for many bodies: buffered_rows) and
!> appended to extendible, chunked datasets
!> when the buffer is full, on particle_output_flush and on particle_output_close.
!> particles.h5 is complete once closed; summary.json, written last via a temporary name, marks a
!> completed run. A restarted run continues the file of the run it continues (particle_output_continue)
!> from the row counts its checkpoint recorded (particle_output_rows, after particle_output_flush).
module particle_output
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use file_system, only: rename_file
  use parallel_env, only: is_root
  use hdf5_files, only: h5_file_t, h5_create, h5_open, h5_close, h5_flush, h5_dataset_names, dataset_name_length
  use hdf5_datasets, only: h5_write_array, h5_write_string, h5_dataset_shape
  use hdf5_series, only: h5_append, h5_truncate
  use json_writer, only: json_object_t, json_add, json_add_null, json_text
  implicit none
  private
  public :: particle_output_t, pair_run_metadata_t, particle_record_t, pair_record_t, collision_event_t, &
            run_summary_t, particle_output_open, particle_output_continue, particle_output_close, &
            particle_output_flush, particle_output_rows, &
            sample_value, sample_end, event_value, event_end, append_pair_sample, append_particles_sample, &
            append_bodies_sample, &
            append_collision_event, &
            write_summary_json, collision_event_columns

  integer, parameter :: buffer_rows = 256

  !> Identity of a pair run, written at the root of particles.h5.
  type :: pair_run_metadata_t
    character(len=256) :: name = ''         !< run name (&run name)
    character(len=16) :: shape = ''         !< 'sphere' | 'needle' | 'disk' | 'spheroid'
    real(wp) :: aspect_ratio = 1.0_wp       !< a/b of the spheroids
    real(wp) :: radius = 0.0_wp             !< m, volume-equivalent radius
    character(len=24) :: fluid = ''         !< 'none' | 'stokes' | 'resolved_point' | 'resolved_resolved'
    integer(i8) :: seed = 0_i8              !< &run seed
    integer :: bodies = 2                   !< number of bodies; > 2 adds /bodies and the events' body columns
  end type pair_run_metadata_t

  !> State and loads of one particle at one output time (lab frame unless stated).
  type :: particle_record_t
    real(wp) :: position(3) = 0.0_wp                 !< m
    real(wp) :: quaternion(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]   !< scalar first, body -> lab
    real(wp) :: velocity(3) = 0.0_wp                 !< m/s
    real(wp) :: angular_velocity(3) = 0.0_wp         !< rad/s
    real(wp) :: force_hydrodynamic(3) = 0.0_wp       !< N
    real(wp) :: force_dlvo(3) = 0.0_wp
    real(wp) :: force_collision(3) = 0.0_wp
    real(wp) :: torque_hydrodynamic(3) = 0.0_wp      !< N m
    real(wp) :: torque_dlvo(3) = 0.0_wp
    real(wp) :: torque_collision(3) = 0.0_wp
  end type particle_record_t

  !> Quantities of one pair (bodies first < second) at one output time.
  type :: pair_record_t
    integer :: first = 1, second = 2        !< the pair's bodies (numbered from 1)
    real(wp) :: gap = 0.0_wp                !< m, signed surface gap (negative = overlap)
    real(wp) :: closest_point1(3) = 0.0_wp  !< m, lab frame
    real(wp) :: closest_point2(3) = 0.0_wp
    real(wp) :: chi_eta = 0.0_wp            !< Eq. 14 curvature factor
    real(wp) :: relative_velocity = 0.0_wp  !< m/s, normal, of the closest points, positive = approaching
    real(wp) :: vdw_force = 0.0_wp          !< N, magnitude of the van der Waals part
  end type pair_record_t

  !> One collision: contact points as parametric angles of each unrotated spheroid (docs/physics.md 0).
  type :: collision_event_t
    real(wp) :: time = 0.0_wp                    !< s
    real(wp) :: theta1 = 0.0_wp, phi1 = 0.0_wp   !< rad, contact point on particle 1
    real(wp) :: theta2 = 0.0_wp, phi2 = 0.0_wp   !< rad, contact point on particle 2
    real(wp) :: normal_velocity_before = 0.0_wp  !< m/s, positive = approaching
    real(wp) :: normal_velocity_after = 0.0_wp
    real(wp) :: psi = 0.0_wp                     !< rad, angle between the symmetry axes, [0, pi/2]
    integer :: first = 1, second = 2             !< the colliding bodies ("particle 1" is first)
  end type collision_event_t

  !> Contents of summary.json (docs/outputs.md).
  type :: run_summary_t
    character(len=256) :: name = ''
    integer(i8) :: seed = 0_i8
    character(len=16) :: shape = ''
    real(wp) :: aspect_ratio = 1.0_wp
    character(len=24) :: fluid = ''
    character(len=16) :: outcome = ''                 !< 'agglomerated' | 'rebounded' | 'approached' | 'no_contact'
    logical :: outcome_settled = .false.              !< false: decided in flight (docs/theory.md, Run outcome)
    logical :: ended_in_flight = .false.              !< the run ended with the outcome not settled
    character(len=16) :: end_rule = ''                !< &pair end_rule: 'settled' | 'paper'
    integer :: collisions = 0                         !< collision impulses (a resting contact: one per step)
    integer :: contact_episodes = 0                   !< contact episodes (rows of /events)
    logical :: has_first_collision = .false.          !< false: "first_collision": null
    type(collision_event_t) :: first_collision
    real(wp) :: max_vdw_force = 0.0_wp                !< N
    real(wp) :: final_gap = 0.0_wp                    !< m
    real(wp) :: final_relative_velocity = 0.0_wp      !< m/s
    real(wp) :: psi_final = 0.0_wp                    !< rad
    real(wp) :: end_time = 0.0_wp                     !< s
    integer(i8) :: steps = 0_i8
    real(wp) :: wall_time = 0.0_wp                    !< s
  end type run_summary_t

  !> Names of the events-table columns written by append_collision_event (under /events); with more
  !> than two bodies also body_columns (the colliding bodies' numbers, stored as reals).
  character(len=*), parameter :: collision_event_columns(8) = [character(len=22) :: 'time', 'theta1', 'phi1', &
      'theta2', 'phi2', 'normal_velocity_before', 'normal_velocity_after', 'psi']
  character(len=*), parameter :: body_columns(2) = [character(len=6) :: 'first', 'second']

  type :: column_t
    character(len=:), allocatable :: name
    integer :: width = 0                     !< 0: scalar column, dataset (N); m: dataset (m, N)
    real(wp), allocatable :: rows(:,:)       !< (max(width, 1), the table's capacity)
    logical :: staged = .false.              !< set in the row being built
  end type column_t

  !> A table of named columns sharing one row count.
  type :: table_t
    character(len=:), allocatable :: group   !< '' or 'events/'
    type(column_t), allocatable :: columns(:)
    logical :: fixed = .false.               !< columns fixed by the first row
    integer :: buffered = 0                  !< rows in the buffers
    integer(i8) :: rows = 0_i8               !< rows committed (written or buffered)
    integer :: capacity = buffer_rows        !< rows held before they are written (buffered_rows)
  end type table_t

  !> An open particles.h5 (only rank 0's copy is active).
  type :: particle_output_t
    type(h5_file_t) :: file
    logical :: active = .false.
    logical :: pair_layout = .false.         !< append_pair_sample used: events table always present
    integer :: bodies = 2                    !< > 2: the events table also has /events/first, /events/second
    type(table_t) :: samples, events
  end type particle_output_t

  !> Stage one value of the row being built (real(wp) scalar or vector).
  interface sample_value
    module procedure sample_scalar, sample_vector
  end interface sample_value

  interface event_value
    module procedure event_scalar, event_vector
  end interface event_value

contains

  !> Create particles.h5 at path (rank 0) and write the run identity at its root:
  !> /name, /shape, /fluid (strings), /aspect_ratio, /radius (m), /seed (integer(i8)).
  subroutine particle_output_open(out, path, metadata)
    type(particle_output_t), intent(out) :: out
    character(len=*), intent(in) :: path
    type(pair_run_metadata_t), intent(in) :: metadata
    out%active = is_root()
    out%samples%group = ''
    out%events%group = 'events/'
    allocate(out%samples%columns(0), out%events%columns(0))
    out%bodies = metadata%bodies
    out%samples%capacity = buffered_rows(metadata%bodies)
    if (.not. out%active) return
    call h5_create(out%file, path, serial=.true.)
    call h5_write_string(out%file, 'name', trim(metadata%name))
    call h5_write_string(out%file, 'shape', trim(metadata%shape))
    call h5_write_string(out%file, 'fluid', trim(metadata%fluid))
    call h5_write_array(out%file, 'aspect_ratio', metadata%aspect_ratio)
    call h5_write_array(out%file, 'radius', metadata%radius)
    call h5_write_array(out%file, 'seed', metadata%seed)
    if (metadata%bodies > 2) call h5_write_array(out%file, 'bodies', int(metadata%bodies, i8))
  end subroutine particle_output_open

  !> Continue the particles.h5 at path of an interrupted or finished run (rank 0): the rows written
  !> after its checkpoint are dropped, so the file holds sample_rows samples and event_rows events
  !> (particle_output_rows when the checkpoint was written) and later rows append to them; the run
  !> identity at the root is kept. Stops with a message if the file has fewer rows.
  subroutine particle_output_continue(out, path, bodies, sample_rows, event_rows)
    type(particle_output_t), intent(out) :: out
    character(len=*), intent(in) :: path
    integer, intent(in) :: bodies                  !< as in the metadata the file was opened with
    integer(i8), intent(in) :: sample_rows, event_rows
    character(len=dataset_name_length), allocatable :: names(:)
    integer :: i
    out%active = is_root()
    out%samples%group = ''
    out%events%group = 'events/'
    allocate(out%samples%columns(0), out%events%columns(0))
    out%bodies = bodies
    out%samples%capacity = buffered_rows(bodies)
    out%samples%rows = sample_rows
    out%events%rows = event_rows
    if (.not. out%active) return
    call h5_open(out%file, path, writable=.true., serial=.true.)
    call h5_dataset_names(out%file, names)
    do i = 1, size(names)
      if (size(h5_dataset_shape(out%file, trim(names(i)))) == 0) cycle   ! the run identity (scalars)
      if (names(i)(1:len(out%events%group)) == out%events%group) then
        call h5_truncate(out%file, trim(names(i)), int(event_rows))
      else
        call h5_truncate(out%file, trim(names(i)), int(sample_rows))
      end if
    end do
  end subroutine particle_output_continue

  !> Sample rows held in memory for a run of the given bodies: buffer_rows, fewer when a row of all
  !> bodies (34 values each) would make the buffer larger than 2^21 values (16 MiB).
  pure integer function buffered_rows(bodies)
    integer, intent(in) :: bodies
    buffered_rows = max(1, min(buffer_rows, 2**21 / max(1, 34 * bodies)))
  end function buffered_rows

  !> Rows committed so far (written or buffered; rank 0's count, 0 on the other ranks): the time
  !> series and the events table.
  subroutine particle_output_rows(out, sample_rows, event_rows)
    type(particle_output_t), intent(in) :: out
    integer(i8), intent(out) :: sample_rows, event_rows
    sample_rows = out%samples%rows
    event_rows = out%events%rows
  end subroutine particle_output_rows

  !> Write the buffered rows and push them to disk (a crash loses nothing written before).
  subroutine particle_output_flush(out)
    type(particle_output_t), intent(inout) :: out
    if (.not. out%active) return
    call write_buffered(out%file, out%samples)
    call write_buffered(out%file, out%events)
    call h5_flush(out%file)
  end subroutine particle_output_flush

  subroutine particle_output_close(out)
    type(particle_output_t), intent(inout) :: out
    integer :: i
    if (.not. out%active) return
    call write_buffered(out%file, out%samples)
    call write_buffered(out%file, out%events)
    ! A pair run without collisions still has its (empty) events table.
    if (out%pair_layout .and. .not. out%events%fixed) then
      do i = 1, size(collision_event_columns)
        call h5_append(out%file, 'events/'//trim(collision_event_columns(i)), [real(wp) ::])
      end do
      if (out%bodies > 2) then
        do i = 1, size(body_columns)
          call h5_append(out%file, 'events/'//trim(body_columns(i)), [real(wp) ::])
        end do
      end if
    end if
    call h5_close(out%file)
    out%active = .false.
  end subroutine particle_output_close

  ! ---------------------------------------------------------------------------------------------
  ! Tables of named columns
  ! ---------------------------------------------------------------------------------------------

  !> Index of column name in table, adding it (with width) if the table is not fixed yet.
  integer function column_index(table, name, width)
    type(table_t), intent(inout) :: table
    character(len=*), intent(in) :: name
    integer, intent(in) :: width
    type(column_t) :: column
    character(len=80) :: text
    integer :: i
    do i = 1, size(table%columns)
      if (table%columns(i)%name == trim(name)) then
        if (table%columns(i)%width /= width) then
          write(text, '(a,i0,a,i0)') ' has width ', table%columns(i)%width, ', given ', width
          call fatal('particle_output: column '//table%group//trim(name)//trim(text), collective=.false.)
        end if
        column_index = i
        return
      end if
    end do
    if (table%fixed) call fatal('particle_output: column '//table%group//trim(name)// &
                                ' is not among the columns fixed by the first row', collective=.false.)
    column%name = trim(name)
    column%width = width
    allocate(column%rows(max(width, 1), table%capacity))
    table%columns = [table%columns, column]
    column_index = size(table%columns)
  end function column_index

  subroutine stage(table, name, values, width)
    type(table_t), intent(inout) :: table
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: values(:)
    integer, intent(in) :: width
    integer :: i
    i = column_index(table, name, width)
    if (table%columns(i)%staged) call fatal('particle_output: column '//table%group//trim(name)// &
                                            ' set twice in one row', collective=.false.)
    table%columns(i)%rows(:, table%buffered + 1) = values
    table%columns(i)%staged = .true.
  end subroutine stage

  !> Commit the staged row: every column must have been set.
  subroutine commit_row(file, table)
    type(h5_file_t), intent(in) :: file
    type(table_t), intent(inout) :: table
    integer :: i
    if (size(table%columns) == 0) call fatal('particle_output: an empty row in '//table%group//' (no values set)', &
                                             collective=.false.)
    do i = 1, size(table%columns)
      if (.not. table%columns(i)%staged) call fatal('particle_output: column '//table%group// &
          table%columns(i)%name//' not set in this row', collective=.false.)
      table%columns(i)%staged = .false.
    end do
    table%fixed = .true.
    table%buffered = table%buffered + 1
    table%rows = table%rows + 1
    if (table%buffered == table%capacity) call write_buffered(file, table)
  end subroutine commit_row

  subroutine write_buffered(file, table)
    type(h5_file_t), intent(in) :: file
    type(table_t), intent(inout) :: table
    integer :: i, n
    n = table%buffered
    if (n == 0) return
    do i = 1, size(table%columns)
      associate (column => table%columns(i))
        if (column%width == 0) then
          call h5_append(file, table%group//column%name, column%rows(1, 1:n))
        else
          call h5_append(file, table%group//column%name, column%rows(:, 1:n))
        end if
      end associate
    end do
    table%buffered = 0
  end subroutine write_buffered

  subroutine sample_scalar(out, name, value)
    type(particle_output_t), intent(inout) :: out
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    if (out%active) call stage(out%samples, name, [value], 0)
  end subroutine sample_scalar

  subroutine sample_vector(out, name, values)
    type(particle_output_t), intent(inout) :: out
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: values(:)
    if (out%active) call stage(out%samples, name, values, size(values))
  end subroutine sample_vector

  !> Commit the sample row staged with sample_value.
  subroutine sample_end(out)
    type(particle_output_t), intent(inout) :: out
    if (out%active) call commit_row(out%file, out%samples)
  end subroutine sample_end

  subroutine event_scalar(out, name, value)
    type(particle_output_t), intent(inout) :: out
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    if (out%active) call stage(out%events, name, [value], 0)
  end subroutine event_scalar

  subroutine event_vector(out, name, values)
    type(particle_output_t), intent(inout) :: out
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: values(:)
    if (out%active) call stage(out%events, name, values, size(values))
  end subroutine event_vector

  !> Commit the event row staged with event_value.
  subroutine event_end(out)
    type(particle_output_t), intent(inout) :: out
    if (out%active) call commit_row(out%file, out%events)
  end subroutine event_end

  ! ---------------------------------------------------------------------------------------------
  ! The pair scenes' layout
  ! ---------------------------------------------------------------------------------------------

  !> One row of the time series of a pair: /time, /particle1/..., /particle2/..., /pair/...
  subroutine append_pair_sample(out, time, particles, pair)
    type(particle_output_t), intent(inout) :: out
    real(wp), intent(in) :: time
    type(particle_record_t), intent(in) :: particles(2)
    type(pair_record_t), intent(in) :: pair
    call append_particles_sample(out, time, particles, [pair])
  end subroutine append_pair_sample

  !> One row of the time series of N bodies: /time, /particle<n>/... for n = 1..N, and per pair
  !> /pair/... when N = 2 (the pair layout), /pair<i>_<j>/... otherwise.
  subroutine append_particles_sample(out, time, particles, pairs)
    type(particle_output_t), intent(inout) :: out
    real(wp), intent(in) :: time
    type(particle_record_t), intent(in) :: particles(:)
    type(pair_record_t), intent(in) :: pairs(:)
    character(len=32) :: group
    integer :: n, p
    if (.not. out%active) return
    out%pair_layout = .true.
    call sample_value(out, 'time', time)
    do n = 1, size(particles)
      write(group, '(a,i0,a)') 'particle', n, '/'
      call sample_value(out, trim(group)//'position', particles(n)%position)
      call sample_value(out, trim(group)//'quaternion', particles(n)%quaternion)
      call sample_value(out, trim(group)//'velocity', particles(n)%velocity)
      call sample_value(out, trim(group)//'angular_velocity', particles(n)%angular_velocity)
      call sample_value(out, trim(group)//'force_hydrodynamic', particles(n)%force_hydrodynamic)
      call sample_value(out, trim(group)//'force_dlvo', particles(n)%force_dlvo)
      call sample_value(out, trim(group)//'force_collision', particles(n)%force_collision)
      call sample_value(out, trim(group)//'torque_hydrodynamic', particles(n)%torque_hydrodynamic)
      call sample_value(out, trim(group)//'torque_dlvo', particles(n)%torque_dlvo)
      call sample_value(out, trim(group)//'torque_collision', particles(n)%torque_collision)
    end do
    do p = 1, size(pairs)
      if (size(particles) == 2) then
        group = 'pair/'
      else
        write(group, '(a,i0,a,i0,a)') 'pair', pairs(p)%first, '_', pairs(p)%second, '/'
      end if
      call sample_value(out, trim(group)//'gap', pairs(p)%gap)
      call sample_value(out, trim(group)//'closest_point1', pairs(p)%closest_point1)
      call sample_value(out, trim(group)//'closest_point2', pairs(p)%closest_point2)
      call sample_value(out, trim(group)//'chi_eta', pairs(p)%chi_eta)
      call sample_value(out, trim(group)//'relative_velocity', pairs(p)%relative_velocity)
      call sample_value(out, trim(group)//'vdw_force', pairs(p)%vdw_force)
    end do
    call sample_end(out)
  end subroutine append_particles_sample

  !> One row of the time series of a suspension (N bodies, one dataset per quantity): /time and
  !> /suspension/<quantity> of width 3 N (4 N for the quaternion), body after body, so h5py reads
  !> f['suspension/position'][:].reshape(rows, N, 3). Ten datasets for any N (not ten per body).
  subroutine append_bodies_sample(out, time, particles)
    type(particle_output_t), intent(inout) :: out
    real(wp), intent(in) :: time
    type(particle_record_t), intent(in) :: particles(:)
    integer :: n, k
    if (.not. out%active) return
    out%pair_layout = .true.
    n = size(particles)
    call sample_value(out, 'time', time)
    call sample_value(out, 'suspension/position', [(particles(k)%position, k = 1, n)])
    call sample_value(out, 'suspension/quaternion', [(particles(k)%quaternion, k = 1, n)])
    call sample_value(out, 'suspension/velocity', [(particles(k)%velocity, k = 1, n)])
    call sample_value(out, 'suspension/angular_velocity', [(particles(k)%angular_velocity, k = 1, n)])
    call sample_value(out, 'suspension/force_hydrodynamic', [(particles(k)%force_hydrodynamic, k = 1, n)])
    call sample_value(out, 'suspension/force_dlvo', [(particles(k)%force_dlvo, k = 1, n)])
    call sample_value(out, 'suspension/force_collision', [(particles(k)%force_collision, k = 1, n)])
    call sample_value(out, 'suspension/torque_hydrodynamic', [(particles(k)%torque_hydrodynamic, k = 1, n)])
    call sample_value(out, 'suspension/torque_dlvo', [(particles(k)%torque_dlvo, k = 1, n)])
    call sample_value(out, 'suspension/torque_collision', [(particles(k)%torque_collision, k = 1, n)])
    call sample_end(out)
  end subroutine append_bodies_sample

  !> One row of the events table (/events/<collision_event_columns>, and the bodies with more than two).
  subroutine append_collision_event(out, event)
    type(particle_output_t), intent(inout) :: out
    type(collision_event_t), intent(in) :: event
    if (.not. out%active) return
    out%pair_layout = .true.
    call event_value(out, 'time', event%time)
    call event_value(out, 'theta1', event%theta1)
    call event_value(out, 'phi1', event%phi1)
    call event_value(out, 'theta2', event%theta2)
    call event_value(out, 'phi2', event%phi2)
    call event_value(out, 'normal_velocity_before', event%normal_velocity_before)
    call event_value(out, 'normal_velocity_after', event%normal_velocity_after)
    call event_value(out, 'psi', event%psi)
    if (out%bodies > 2) then
      call event_value(out, 'first', real(event%first, wp))
      call event_value(out, 'second', real(event%second, wp))
    end if
    call event_end(out)
  end subroutine append_collision_event

  ! ---------------------------------------------------------------------------------------------
  ! summary.json
  ! ---------------------------------------------------------------------------------------------

  !> Write summary.json at path (rank 0): to path.tmp first, then renamed, so a reader sees either no
  !> summary or a complete one. Call it last: its presence means the run completed.
  subroutine write_summary_json(path, summary)
    character(len=*), intent(in) :: path
    type(run_summary_t), intent(in) :: summary
    type(json_object_t) :: object, first
    integer :: unit, ios
    logical :: ok
    if (.not. is_root()) return
    select case (trim(summary%outcome))
    case ('agglomerated', 'rebounded', 'approached', 'no_contact')
    case default
      call fatal('particle_output: summary outcome "'//trim(summary%outcome)// &
                 '" is not agglomerated, rebounded, approached or no_contact', collective=.false.)
    end select
    call json_add(object, 'name', trim(summary%name))
    call json_add(object, 'seed', summary%seed)
    call json_add(object, 'shape', trim(summary%shape))
    call json_add(object, 'aspect_ratio', summary%aspect_ratio)
    call json_add(object, 'fluid', trim(summary%fluid))
    call json_add(object, 'outcome', trim(summary%outcome))
    call json_add(object, 'outcome_settled', summary%outcome_settled)
    call json_add(object, 'ended_in_flight', summary%ended_in_flight)
    call json_add(object, 'end_rule', trim(summary%end_rule))
    call json_add(object, 'collisions', summary%collisions)
    call json_add(object, 'contact_episodes', summary%contact_episodes)
    if (summary%has_first_collision) then
      call json_add(first, 'time', summary%first_collision%time)
      call json_add(first, 'theta1', summary%first_collision%theta1)
      call json_add(first, 'phi1', summary%first_collision%phi1)
      call json_add(first, 'theta2', summary%first_collision%theta2)
      call json_add(first, 'phi2', summary%first_collision%phi2)
      call json_add(first, 'psi', summary%first_collision%psi)
      call json_add(first, 'normal_velocity_before', summary%first_collision%normal_velocity_before)
      call json_add(first, 'normal_velocity_after', summary%first_collision%normal_velocity_after)
      call json_add(object, 'first_collision', first)
    else
      call json_add_null(object, 'first_collision')
    end if
    call json_add(object, 'max_vdw_force', summary%max_vdw_force)
    call json_add(object, 'final_gap', summary%final_gap)
    call json_add(object, 'final_relative_velocity', summary%final_relative_velocity)
    call json_add(object, 'psi_final', summary%psi_final)
    call json_add(object, 'end_time', summary%end_time)
    call json_add(object, 'steps', summary%steps)
    call json_add(object, 'wall_time', summary%wall_time)
    open(newunit=unit, file=trim(path)//'.tmp', status='replace', action='write', iostat=ios)
    if (ios /= 0) call fatal('particle_output: cannot write '//trim(path)//'.tmp', collective=.false.)
    write(unit, '(a)') json_text(object)
    close(unit)
    call rename_file(trim(path)//'.tmp', path, ok)
    if (.not. ok) call fatal('particle_output: cannot rename '//trim(path)//'.tmp', collective=.false.)
  end subroutine write_summary_json
end module particle_output
