/* dpsm/bmi.h compiles alone, twice, and after a framework's own bmi.h (the
 * include guard BMI_H, the same struct): a host that holds CSDMS's header
 * can include ours too. Compiled with -DWITH_FRAMEWORK_BMI_H and without. */
#ifdef WITH_FRAMEWORK_BMI_H
#ifndef BMI_H
#define BMI_H
#define BMI_SUCCESS (0)
#define BMI_FAILURE (1)
typedef struct Bmi {
    void *data;
    int (*initialize)(struct Bmi *self, const char *config_file);
} Bmi;
#endif
#endif

#include <dpsm/bmi.h>
#include <dpsm/bmi.h>

Bmi *(*const registration_under_its_own_name)(Bmi *) = register_bmi_dpsm;
Bmi *(*const registration_for_nextgen)(Bmi *) = register_bmi;
int success_is_zero[BMI_SUCCESS == 0 ? 1 : -1];
