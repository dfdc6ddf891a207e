/* Package registration: the class id and one log event per pipeline operation, so -log_view
   shows where the time goes. Registered once; names stay within 16 characters. */
#include <pff.h>

PetscClassId  PFF_CLASSID;
PetscLogEvent PFF_GridSetUp, PFF_GridAdapt, PFF_GridRefine, PFF_GridPartition, PFF_HaloSetUp, PFF_HaloBegin,
    PFF_HaloEnd, PFF_HaloRevBegin, PFF_HaloRevEnd, PFF_GridInterp, PFF_GridLaplacian, PFF_IOWrite, PFF_IORead,
    PFF_PartSeed, PFF_PartAdapt, PFF_FlowAdaptDist, PFF_FlowAdaptMap, PFF_PartBin, PFF_PartMigrate, PFF_P2G, PFF_G2P,
    PFF_Advect, PFF_PressSetUp, PFF_PressAssemble, PFF_PressSolve, PFF_PhaseField, PFF_Forces, PFF_FlowExtrap,
    PFF_CkptWrite, PFF_CkptRead, PFF_MGSetUp, PFF_MGApply, PFF_MGSmooth, PFF_MGCoarse, PFF_FlowRefBodies, PFF_TallBuild,
    PFF_TallSizing, PFF_FlowBandAdvect, PFF_FlowBandSeed, PFF_FlowBandDist;
PetscLogEvent PFF_MGLevel[PFF_MG_LOG_LEVELS];

static PetscBool PffPackageInitialized = PETSC_FALSE;

PetscErrorCode PffInitializePackage(void)
{
  PetscFunctionBeginUser;
  if (PffPackageInitialized) PetscFunctionReturn(PETSC_SUCCESS);
  PffPackageInitialized = PETSC_TRUE;
  PetscCall(PetscClassIdRegister("PFF", &PFF_CLASSID));
  PetscCall(PetscLogEventRegister("GridSetUp", PFF_CLASSID, &PFF_GridSetUp));
  PetscCall(PetscLogEventRegister("GridAdapt", PFF_CLASSID, &PFF_GridAdapt));
  PetscCall(PetscLogEventRegister("GridRefine", PFF_CLASSID, &PFF_GridRefine));
  PetscCall(PetscLogEventRegister("GridPartition", PFF_CLASSID, &PFF_GridPartition));
  PetscCall(PetscLogEventRegister("HaloSetUp", PFF_CLASSID, &PFF_HaloSetUp));
  PetscCall(PetscLogEventRegister("HaloBegin", PFF_CLASSID, &PFF_HaloBegin));
  PetscCall(PetscLogEventRegister("HaloEnd", PFF_CLASSID, &PFF_HaloEnd));
  PetscCall(PetscLogEventRegister("HaloRevBegin", PFF_CLASSID, &PFF_HaloRevBegin));
  PetscCall(PetscLogEventRegister("HaloRevEnd", PFF_CLASSID, &PFF_HaloRevEnd));
  PetscCall(PetscLogEventRegister("GridInterp", PFF_CLASSID, &PFF_GridInterp));
  PetscCall(PetscLogEventRegister("GridLaplacian", PFF_CLASSID, &PFF_GridLaplacian));
  PetscCall(PetscLogEventRegister("IOWrite", PFF_CLASSID, &PFF_IOWrite));
  PetscCall(PetscLogEventRegister("IORead", PFF_CLASSID, &PFF_IORead));
  PetscCall(PetscLogEventRegister("PartSeed", PFF_CLASSID, &PFF_PartSeed));
  PetscCall(PetscLogEventRegister("PartAdapt", PFF_CLASSID, &PFF_PartAdapt));
  PetscCall(PetscLogEventRegister("FlowAdaptDist", PFF_CLASSID, &PFF_FlowAdaptDist));
  PetscCall(PetscLogEventRegister("FlowAdaptMap", PFF_CLASSID, &PFF_FlowAdaptMap));
  PetscCall(PetscLogEventRegister("PartBin", PFF_CLASSID, &PFF_PartBin));
  PetscCall(PetscLogEventRegister("PartMigrate", PFF_CLASSID, &PFF_PartMigrate));
  PetscCall(PetscLogEventRegister("P2G", PFF_CLASSID, &PFF_P2G));
  PetscCall(PetscLogEventRegister("G2P", PFF_CLASSID, &PFF_G2P));
  PetscCall(PetscLogEventRegister("Advect", PFF_CLASSID, &PFF_Advect));
  PetscCall(PetscLogEventRegister("PressSetUp", PFF_CLASSID, &PFF_PressSetUp));
  PetscCall(PetscLogEventRegister("PressAssemble", PFF_CLASSID, &PFF_PressAssemble));
  PetscCall(PetscLogEventRegister("PressSolve", PFF_CLASSID, &PFF_PressSolve));
  PetscCall(PetscLogEventRegister("PhaseField", PFF_CLASSID, &PFF_PhaseField));
  PetscCall(PetscLogEventRegister("Forces", PFF_CLASSID, &PFF_Forces));
  PetscCall(PetscLogEventRegister("FlowExtrapolate", PFF_CLASSID, &PFF_FlowExtrap));
  PetscCall(PetscLogEventRegister("FlowRefBodies", PFF_CLASSID, &PFF_FlowRefBodies));
  PetscCall(PetscLogEventRegister("TallBuild", PFF_CLASSID, &PFF_TallBuild));
  PetscCall(PetscLogEventRegister("TallSizing", PFF_CLASSID, &PFF_TallSizing));
  PetscCall(PetscLogEventRegister("FlowBandAdvect", PFF_CLASSID, &PFF_FlowBandAdvect));
  PetscCall(PetscLogEventRegister("FlowBandSeed", PFF_CLASSID, &PFF_FlowBandSeed));
  PetscCall(PetscLogEventRegister("FlowBandDist", PFF_CLASSID, &PFF_FlowBandDist));
  PetscCall(PetscLogEventRegister("CkptWrite", PFF_CLASSID, &PFF_CkptWrite));
  PetscCall(PetscLogEventRegister("CkptRead", PFF_CLASSID, &PFF_CkptRead));
  PetscCall(PetscLogEventRegister("MGSetUp", PFF_CLASSID, &PFF_MGSetUp));
  PetscCall(PetscLogEventRegister("MGApply", PFF_CLASSID, &PFF_MGApply));
  PetscCall(PetscLogEventRegister("MGSmooth", PFF_CLASSID, &PFF_MGSmooth));
  PetscCall(PetscLogEventRegister("MGCoarse", PFF_CLASSID, &PFF_MGCoarse));
  for (int L = 0; L < PFF_MG_LOG_LEVELS; L++) {
    char name[16];
    PetscCall(PetscSNPrintf(name, sizeof(name), "MGLevel%d%s", L, L == PFF_MG_LOG_LEVELS - 1 ? "+" : ""));
    PetscCall(PetscLogEventRegister(name, PFF_CLASSID, &PFF_MGLevel[L]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
