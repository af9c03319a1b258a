!> Namelist group &scene: which models the run switches on (docs/design.md, "Fidelity").
!> Nothing that is off is allocated or computed.
module config_scene
  use deck_file, only: deck_t, check_namelist_read, require_option, require_positive_int
  implicit none
  private
  public :: scene_config_t, read_scene_group, check_scene_group, write_scene_group

  type :: scene_config_t
    character(len=16) :: fluid = 'resolved'       !< 'none' | 'stokes' | 'resolved'
    !> 'none' | 'pair' | 'prescribed' (&bodies, resolved fluid) | 'free' (free bodies placed by &bodies,
    !> resolved fluid) | 'suspension' (free bodies placed at random by &suspension, any fluid)
    character(len=16) :: particles = 'none'
    character(len=16) :: forcing = 'none'         !< 'none' | 'eswaran_pope' (resolved fluid only)
    character(len=16) :: ibm_coupling = 'implicit' !< 'implicit' | 'explicit' (resolved fluid with particles)
    logical :: dlvo = .true.                      !< DLVO forces between the particles
    logical :: collisions = .true.                !< hard-body collisions between the particles
    integer :: particle_substeps = 1              !< particle steps per fluid step (frozen loads)
    !> How the free particles (the pair, 'free' bodies or a suspension) in the resolved fluid feel it: 'point'
    !> (analytic Stokes resistance in the flow at each centre, the fluid solved without the bodies) |
    !> 'resolved' (free particles resolved by the immersed boundary)
    character(len=16) :: particle_coupling = 'resolved'
    logical :: added_mass = .false.               !< particle_coupling = 'point': implicit added-mass term
    !> particle_coupling = 'resolved', explicit diffusion: the stabilisation's history estimate
    logical :: added_mass_history = .false.
    !> Which bodies take the particle sub-steps: 'all' | 'near' (particle_coupling = 'point', a
    !> suspension: only the bodies of the pairs that may come within the interaction gap in this fluid
    !> step; the others take the fluid step in one exact exponential update, module point_free_step)
    character(len=8) :: substep_bodies = 'all'
  end type scene_config_t

  character(len=16) :: fluid, particles, forcing, ibm_coupling, particle_coupling
  character(len=8) :: substep_bodies
  logical :: dlvo, collisions, added_mass, added_mass_history
  integer :: particle_substeps
  namelist /scene/ fluid, particles, forcing, ibm_coupling, dlvo, collisions, particle_substeps, particle_coupling, &
                   added_mass, added_mass_history, substep_bodies

contains

  subroutine to_namelist(cfg)
    type(scene_config_t), intent(in) :: cfg
    fluid = cfg%fluid; particles = cfg%particles; forcing = cfg%forcing; ibm_coupling = cfg%ibm_coupling
    dlvo = cfg%dlvo; collisions = cfg%collisions; particle_substeps = cfg%particle_substeps
    particle_coupling = cfg%particle_coupling; added_mass = cfg%added_mass; added_mass_history = cfg%added_mass_history
    substep_bodies = cfg%substep_bodies
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(scene_config_t), intent(inout) :: cfg
    cfg%fluid = fluid; cfg%particles = particles; cfg%forcing = forcing; cfg%ibm_coupling = ibm_coupling
    cfg%dlvo = dlvo; cfg%collisions = collisions; cfg%particle_substeps = particle_substeps
    cfg%particle_coupling = particle_coupling; cfg%added_mass = added_mass; cfg%added_mass_history = added_mass_history
    cfg%substep_bodies = substep_bodies
  end subroutine from_namelist

  subroutine read_scene_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(scene_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=scene, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'scene', ios, message)
    call from_namelist(cfg)
  end subroutine read_scene_group

  subroutine check_scene_group(cfg)
    type(scene_config_t), intent(in) :: cfg
    call require_option('scene', 'fluid', cfg%fluid, [character(len=8) :: 'none', 'stokes', 'resolved'])
    call require_option('scene', 'particles', cfg%particles, &
                        [character(len=10) :: 'none', 'pair', 'prescribed', 'free', 'suspension'])
    call require_option('scene', 'forcing', cfg%forcing, [character(len=12) :: 'none', 'eswaran_pope'])
    call require_option('scene', 'ibm_coupling', cfg%ibm_coupling, [character(len=8) :: 'implicit', 'explicit'])
    call require_positive_int('scene', 'particle_substeps', cfg%particle_substeps)
    call require_option('scene', 'particle_coupling', cfg%particle_coupling, [character(len=8) :: 'point', 'resolved'])
    call require_option('scene', 'substep_bodies', cfg%substep_bodies, [character(len=4) :: 'all', 'near'])
  end subroutine check_scene_group

  subroutine write_scene_group(unit, cfg)
    integer, intent(in) :: unit
    type(scene_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=scene)
  end subroutine write_scene_group
end module config_scene
