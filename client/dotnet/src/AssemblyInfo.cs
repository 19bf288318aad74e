using System.Reflection;
using System.Runtime.CompilerServices;

[assembly: AssemblyTitle("vcinet2")]
[assembly: AssemblyDescription("The IXXAT VCI .NET API (VCI 3: Ixxat.Vci3) on canemu's libvcinpl2.so")]
[assembly: AssemblyProduct("canemu")]
[assembly: AssemblyVersion("3.5.0.0")]
