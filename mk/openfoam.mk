# OpenFOAM (ESI v1912, Debian's `openfoam` package): installed only when missing, then checked.
#
# Debian puts the applications in /usr/bin but sets no environment; its etc/bashrc cannot
# be sourced (it calls helper scripts the package does not ship).  The applications only
# need WM_PROJECT_DIR=/usr/share/openfoam, which rotorflow.cases.foam sets itself, so
# nothing has to be sourced.  A sourced OpenFOAM (rhoSimpleFoam on PATH) is used as is.

FOAM_PROBE := rhoSimpleFoam
FOAM_DEB := openfoam
# apt-get needs root: sudo when not root (CI containers run as root).
FOAM_SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: openfoam

openfoam: $(STAMP) ## install OpenFOAM (Debian openfoam, v1912) if missing; check a solver runs
	@if command -v $(FOAM_PROBE) >/dev/null 2>&1; then \
	  echo "openfoam: $(FOAM_PROBE) found at $$(command -v $(FOAM_PROBE))"; \
	elif command -v apt-get >/dev/null 2>&1; then \
	  echo "openfoam: installing Debian's $(FOAM_DEB) package"; \
	  $(FOAM_SUDO) apt-get update -qq; \
	  DEBIAN_FRONTEND=noninteractive $(FOAM_SUDO) apt-get install -y -qq --no-install-recommends $(FOAM_DEB) >/dev/null; \
	else \
	  echo "openfoam: $(FOAM_PROBE) not found and no apt-get to install $(FOAM_DEB) with" >&2; exit 2; \
	fi
	$(PY) -m rotorflow.cases.foam
