#include <dpsm/dpsm.h>
