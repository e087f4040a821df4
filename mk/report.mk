# The report's system packages (Debian), installed only when missing, then checked:
#  - chromium: the test that opens the demo report headless and checks every picture loads;
#  - Mesa's EGL (libegl1, libegl-mesa0, libgl1-mesa-dri) and libxrender1: pyvista/VTK render
#    the rotor pictures off-screen through EGL, with no X display.
# The Python side (pyvista, dask[distributed], dask-jobqueue) comes with the venv.

REPORT_DEBS := chromium libegl1 libegl-mesa0 libgl1-mesa-dri libgl1 libxrender1 fonts-dejavu-core
REPORT_SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: report-deps

report-deps: ## install what the report needs from Debian (chromium, Mesa EGL) if missing
	@missing=""; \
	for p in $(REPORT_DEBS); do \
	  dpkg-query -W -f='$${Status}' "$$p" 2>/dev/null | grep -q "ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -z "$$missing" ]; then \
	  echo "report-deps: all there"; \
	elif command -v apt-get >/dev/null 2>&1; then \
	  echo "report-deps: installing$$missing"; \
	  $(REPORT_SUDO) apt-get update -qq; \
	  DEBIAN_FRONTEND=noninteractive $(REPORT_SUDO) apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	else \
	  echo "report-deps: missing$$missing and no apt-get to install them with" >&2; exit 2; \
	fi
	@command -v chromium >/dev/null || { echo "report-deps: chromium is not on PATH" >&2; exit 2; }

# The tests open the demo report in chromium; the report target renders with pyvista.
test: report-deps
report: report-deps
