// The one table of diagnostic codes, for the language (L, P, E, W30x: lang/diagnostics.h
// reports them), the compiler (K3xx, W31x: rt::CompileMessage) and the URDF importer (U4xx:
// import/diagnostics.h). It lives in the flat
// layer, the contract both sides include, so that the compiler names its codes without
// seeing the language; both are rendered by lang::Diagnostics::Render.
#pragma once

namespace kanesim::flat {

// X(enumerator, "code", one-line summary). A summary starting "internal:" marks a code no
// model can cause (an API misuse or an internal failure); every other code has a test file
// in tests/lang/diagnostics/.
// Codes are stable: tests and users refer to them. Add new ones at the end of a group.
#define KANESIM_DIAGNOSTICS(X)                                                                \
  /* lexer */                                                                                 \
  X(UnexpectedChar, "L001", "unexpected character")                                           \
  X(UnterminatedString, "L002", "unterminated string literal")                                \
  X(UnterminatedComment, "L003", "unterminated block comment")                                \
  X(BadNumber, "L004", "malformed number")                                                    \
  X(FileTooLarge, "L005", "file too large")                                                   \
  /* parser */                                                                                \
  X(ExpectedToken, "P101", "unexpected token")                                                \
  X(UnclosedBracket, "P102", "unclosed bracket")                                              \
  X(EndNameMismatch, "P103", "end name does not match the class name")                       \
  X(NestingTooDeep, "P104", "nesting too deep")                                               \
  X(TooManyErrors, "P105", "too many errors or warnings")                                     \
  X(ExpressionTooDeep, "P106", "expression too deep (operator chain too long)")               \
  /* elaboration */                                                                           \
  X(UnknownName, "E201", "unknown name")                                                      \
  X(UnknownClass, "E202", "unknown class")                                                    \
  X(UnknownModifier, "E203", "modifier names no element of the class")                       \
  X(TypeMismatch, "E204", "type mismatch")                                                    \
  X(SizeMismatch, "E205", "array size mismatch")                                              \
  X(FinalOverride, "E206", "modification of a final element")                                \
  X(RecursiveExtends, "E207", "recursive extends")                                            \
  X(Duplicate, "E208", "duplicate declaration")                                               \
  X(ArrayTooLarge, "E209", "array too large")                                                 \
  X(BadSet, "E210", "bad --set value")                                                        \
  X(NotParameter, "E211", "not a parameter")                                                  \
  X(BadConnect, "E212", "connect needs two frame connectors")                                 \
  X(BadValue, "E213", "parameter value out of range or not finite")                          \
  X(BadCall, "E214", "unknown function or wrong arguments")                                   \
  X(NotConstantExpr, "E215", "expression must be a parameter expression")                    \
  X(BadEquation, "E216", "equation kind not supported")                                       \
  X(WorldCount, "E217", "a mechanism needs exactly one World")                               \
  X(NotReplaceable, "E218", "redeclare of an element that is not replaceable")               \
  X(IndexOutOfRange, "E219", "index out of range")                                            \
  X(MissingValue, "E220", "parameter has no value")                                           \
  X(NotAModel, "E221", "no model to elaborate")                                               \
  X(InstanceTooLarge, "E222", "model too large")                                              \
  X(BadPrimitive, "E223", "invalid primitive declaration")                                    \
  X(PartialInstance, "E224", "instance of a partial class")                                   \
  X(BadImport, "E225", "import names nothing")                                                \
  X(ConflictingEquation, "E226", "conflicting equations")                                     \
  X(Circular, "E227", "circular definition")                                                  \
  X(WorkLimit, "E228", "elaboration exceeds its work limit")                                  \
  X(EvalTooDeep, "E229", "evaluation nested too deep")                                        \
  /* meshes (MeshBody; lang/elab_mesh.cpp) */                                                \
  X(MeshFileMissing, "E230", "mesh file not found")                                           \
  X(MeshUnreadable, "E231", "mesh file cannot be read")                                       \
  X(MeshTooLarge, "E232", "mesh over a size limit")                                           \
  X(MeshNotClosed, "E233", "mesh surface not closed")                                         \
  X(MeshOrientation, "E234", "mesh triangles inconsistently oriented")                        \
  X(MeshZeroVolume, "E235", "mesh encloses no volume")                                        \
  /* units of measure (lang/elab_units.cpp) */                                                \
  X(BadUnit, "E236", "unit string not understood")                                            \
  X(UnitMismatch, "E237", "units do not agree")                                               \
  X(UnitConflict, "E238", "a variable without a unit is used in two different units")         \
  X(UnconnectedInput, "E239", "input is not connected: nothing gives its value")              \
  X(UnconnectedFrame, "W301", "frame connector is not connected")                            \
  X(MeshInsideOut, "W302", "mesh triangles face inward (flipped)")                            \
  X(MeshDegenerate, "W303", "mesh has degenerate or non-manifold parts")                      \
  /* compiler (compiler): the flat mechanism cannot be made a program */                \
  X(RebindCount, "K300", "internal: rt::Rebind given the wrong number of parameter values")   \
  X(WorldMissing, "K301", "internal: no world, or more than one (E217 comes first)")                                       \
  X(NotAttached, "K302", "element not attached to a frame")                                   \
  X(NotConnectedToWorld, "K303", "not connected to the world")                                \
  X(NotFixed, "K304", "internal: a fixed number depends on time or state (E215, E216 first)")                              \
  X(BadPrescribed, "K305", "prescribed motion of a joint whose speeds are not rates")         \
  X(Degenerate, "K306", "negative mass, zero axis or zero quaternion")                        \
  X(NotSimulated, "K307", "expression reads a quantity that is not simulated")               \
  X(BadMassProperties, "K308", "mass properties no rigid body has")                           \
  X(MovesNoMass, "K309", "joint moves no mass (its motion has no inertia)")                 \
  X(CannotAssemble, "K310", "closed loop or contact cannot be assembled at the start")         \
  X(BadContact, "K311", "invalid contact")                                                    \
  X(BadFriction, "K312", "friction on a joint that cannot take it")                           \
  X(IndeterminateSignals, "W313", "statically indeterminate constraint-force components")    \
  X(FrictionIndeterminate, "W314", "friction reads an indeterminate normal force")            \
  X(StartSpeedsProjected, "W315", "start speeds changed to satisfy the velocity constraints")  \
  X(LockedJoint, "W316", "joint cannot move: both its frames are on one rigid body")          \
  X(OutOfRange, "K317", "mass, inertia or length out of the range the equations can use")  \
  X(BadStop, "K318", "end stop on a joint that cannot take it, or out of order")            \
  X(SparseAnalysis, "K320", "internal: the sparse solver's structural analysis failed")         \
  X(BadCoupling, "K319", "joint coupling on joints that cannot take it")                            \
  X(BadReinit, "K321", "when clause or reinit the mechanism cannot take")                         \
  /* URDF import (import/): a robot file that cannot be translated (docs/import.md) */       \
  X(UrdfBadXml, "U401", "malformed XML")                                                      \
  X(UrdfNotUrdf, "U402", "not a URDF robot")                                                  \
  X(UrdfMissing, "U403", "missing element or attribute")                                      \
  X(UrdfBadNumber, "U404", "number malformed, not finite or out of range")                    \
  X(UrdfDuplicateName, "U405", "duplicate link or joint name")                                \
  X(UrdfUnknownLink, "U406", "joint names a link or joint that does not exist")               \
  X(UrdfNotATree, "U407", "links and joints do not form one tree")                            \
  X(UrdfBadJointType, "U408", "unknown joint type")                                           \
  X(UrdfTooLarge, "U409", "file over a size limit")                                           \
  X(UrdfEntities, "U410", "DTD entity declarations are not read")                             \
  X(UrdfReaderMissing, "U411", "internal: the URDF reader library cannot be loaded (an installation, not a model)") \
  X(UrdfBadMimic, "U412", "mimic between joints that cannot be coupled")

enum class DiagCode {
#define KANESIM_X(e, code, summary) e,
  KANESIM_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
};

const char* DiagCodeString(DiagCode c);   // "E203"
const char* DiagCodeSummary(DiagCode c);

}  // namespace kanesim::flat
